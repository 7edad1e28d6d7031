#include "talus/solver/grid_update.hpp"

#include <array>
#include <vector>

namespace talus {

namespace {

/// Runs node_update(n, node_ijk) on every node of every active tile in parallel; sums the returned
/// energies tile by tile in a fixed order, so the total does not depend on the thread count.
template <class NodeUpdate>
double for_active_nodes(const Grid& grid, NodeUpdate node_update) {
  const auto& tiles = grid.active_tiles();
  const std::size_t count = tiles.size();
  std::vector<double> tile_energy(count, 0.0);
#pragma omp parallel for schedule(static)
  for (std::size_t t = 0; t < count; ++t) {
    double energy = 0.0;
    const std::size_t begin = static_cast<std::size_t>(tiles[t]) * kTileNodes;
    for (int s = 0; s < kTileNodes; ++s) energy += node_update(begin + s, tiles[t], s);
    tile_energy[t] = energy;
  }
  double total = 0.0;
  for (double e : tile_energy) total += e;
  return total;
}

}  // namespace

double update_grid(Grid& grid, const Walls& walls, const Vec3& gravity, double dt, double mass_floor) {
  return for_active_nodes(grid, [&](std::size_t n, std::uint32_t tile, int slot) {
    const double m = grid.mass[n];
    if (m <= mass_floor) {
      for (int d = 0; d < 3; ++d) grid.momentum[d][n] = grid.force[d][n] = grid.velocity_l[d][n] = 0.0;
      return 0.0;
    }
    double v[3], vl[3];
    for (int d = 0; d < 3; ++d) {
      v[d] = grid.momentum[d][n] / m;
      vl[d] = v[d] + (grid.force[d][n] / m + gravity[d]) * dt;
    }
    double removed = 0.0;
    const auto node = grid.node_of(tile, slot);
    if (walls.touches(node)) removed = walls.apply(node, vl, Walls::Stage::GridUpdate, m, v);
    for (int d = 0; d < 3; ++d) {
      grid.momentum[d][n] = v[d];
      grid.force[d][n] = vl[d] - v[d];
      grid.velocity_l[d][n] = vl[d];
    }
    return removed;
  });
}

namespace {

/// v = momentum / m with the walls at `stage`, written into `target` (zero on empty nodes). For the
/// remap, `velocity_l` still holds this step's v^L: the contact state of the grid update.
void wall_projected_velocities(Grid& grid, const Walls& walls, double mass_floor, Walls::Stage stage,
                               std::array<LazyArray, 3>& target) {
  for_active_nodes(grid, [&](std::size_t n, std::uint32_t tile, int slot) {
    const double m = grid.mass[n];
    if (m <= mass_floor) {
      for (int d = 0; d < 3; ++d) target[d][n] = 0.0;
      return 0.0;
    }
    double v[3] = {grid.momentum[0][n] / m, grid.momentum[1][n] / m, grid.momentum[2][n] / m};
    const auto node = grid.node_of(tile, slot);
    if (walls.touches(node)) {
      const double vl[3] = {grid.velocity_l[0][n], grid.velocity_l[1][n], grid.velocity_l[2][n]};
      walls.apply(node, v, stage, 0.0, nullptr, vl);
    }
    for (int d = 0; d < 3; ++d) target[d][n] = v[d];
    return 0.0;
  });
}

}  // namespace

void velocities_from_momentum(Grid& grid, const Walls& walls, double mass_floor) {
  wall_projected_velocities(grid, walls, mass_floor, Walls::Stage::Remap, grid.momentum);
}

void start_velocities(Grid& grid, const Walls& walls, double mass_floor) {
  wall_projected_velocities(grid, walls, mass_floor, Walls::Stage::Start, grid.velocity_l);
}

}  // namespace talus
