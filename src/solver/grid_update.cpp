#include "talus/solver/grid_update.hpp"

#include <array>
#include <vector>

namespace talus {

namespace {

/// node_update(n, node) on every node of active tile t, in slot order (n: the node's index, node: its
/// (i, j, k)); returns the sum of what it returns (the tile's energy).
template <class NodeUpdate>
double for_tile_nodes(const Grid& grid, std::size_t t, NodeUpdate&& node_update) {
  const std::uint32_t tile = grid.active_tiles()[t];
  const std::size_t begin = static_cast<std::size_t>(tile) * kTileNodes;
  const std::array<int, 3> first = grid.node_of(tile);
  double energy = 0.0;
  for (int s = 0; s < kTileNodes; ++s)
    energy += node_update(begin + s, Grid::node_in_tile(first, s));
  return energy;
}

}  // namespace

void add_grid_update(TileStages& stages, Grid& grid, const Walls& walls, const Vec3& gravity, double dt,
                     double mass_floor, bool zero_momentum, std::vector<double>& tile_work) {
  tile_work.assign(grid.active_tiles().size(), 0.0);
  stages.add(TileReach::OwnTile, [&grid, &walls, &tile_work, gravity, dt, mass_floor, zero_momentum](std::size_t t) {
    tile_work[t] = for_tile_nodes(grid, t, [&](std::size_t n, const std::array<int, 3>& node) {
      // the node's record and its v^L record, read and written in place (NodeField's run-time
      // stride made this loop 1.8x slower)
      double* const record = grid.record(n);
      double* const lagrangian = grid.lagrangian_record(n);
      const double m = record[kMassSlot];
      if (m <= mass_floor) {
        for (int d = 0; d < 3; ++d) record[kMomentumSlot + d] = record[kForceSlot + d] = lagrangian[d] = 0.0;
        return 0.0;
      }
      double v[3], vl[3];
      for (int d = 0; d < 3; ++d) {
        v[d] = record[kMomentumSlot + d] / m;
        vl[d] = v[d] + (record[kForceSlot + d] / m + gravity[d]) * dt;
      }
      double removed = 0.0;
      if (walls.touches(node)) removed = walls.apply(node, vl, Walls::Stage::GridUpdate, m, v);
      for (int d = 0; d < 3; ++d) {
        record[kMomentumSlot + d] = zero_momentum ? 0.0 : v[d];
        record[kForceSlot + d] = vl[d] - v[d];
        lagrangian[d] = vl[d];
      }
      return removed;
    });
  });
}

double counted_work(const std::vector<double>& tile_work, const std::vector<std::uint8_t>& counted) {
  double total = 0.0;
  for (std::size_t t = 0; t < tile_work.size(); ++t)
    if (counted.empty() || counted[t]) total += tile_work[t];
  return total;
}

double update_grid(Grid& grid, const Walls& walls, const Vec3& gravity, double dt, double mass_floor,
                   const std::vector<std::uint8_t>& counted, bool zero_momentum) {
  TileStages stages(grid.active_tiles().size());
  std::vector<double> tile_work;
  add_grid_update(stages, grid, walls, gravity, dt, mass_floor, zero_momentum, tile_work);
  stages.run();
  return counted_work(tile_work, counted);
}

namespace {

/// v = momentum / m with the walls at `stage`, written into `target` (zero on empty nodes). For the
/// remap, `velocity_l` still holds this step's v^L: the contact state of the grid update.
void add_wall_projected_velocities(TileStages& stages, Grid& grid, const Walls& walls, double mass_floor,
                                   Walls::Stage stage, NodeVectors& target) {
  stages.add(TileReach::OwnTile, [&grid, &walls, &target, mass_floor, stage](std::size_t t) {
    for_tile_nodes(grid, t, [&](std::size_t n, const std::array<int, 3>& node) {
      const double m = grid.mass[n];
      if (m <= mass_floor) {
        for (int d = 0; d < 3; ++d) target[d][n] = 0.0;
        return 0.0;
      }
      double v[3] = {grid.momentum[0][n] / m, grid.momentum[1][n] / m, grid.momentum[2][n] / m};
      if (walls.touches(node)) {
        const double vl[3] = {grid.velocity_l[0][n], grid.velocity_l[1][n], grid.velocity_l[2][n]};
        walls.apply(node, v, stage, 0.0, nullptr, vl);
      }
      for (int d = 0; d < 3; ++d) target[d][n] = v[d];
      return 0.0;
    });
  });
}

}  // namespace

void add_velocities_from_momentum(TileStages& stages, Grid& grid, const Walls& walls, double mass_floor) {
  add_wall_projected_velocities(stages, grid, walls, mass_floor, Walls::Stage::Remap, grid.momentum);
}

void add_start_velocities(TileStages& stages, Grid& grid, const Walls& walls, double mass_floor) {
  add_wall_projected_velocities(stages, grid, walls, mass_floor, Walls::Stage::Start, grid.velocity_l);
}

void add_fold_ghost_nodes(TileStages& stages, Grid& grid, const GhostMap& ghosts, ScatteredFields fields,
                          const Vec3& gravity) {
  if (ghosts.empty()) return;
  stages.add(TileReach::AnyTile, [&grid, &ghosts, fields, gravity](std::size_t t) {
    const auto [mass, momentum, force] = fields;
    // the tile's nodes in slot order, each with the ghosts whose image it is (Walls::ghosts_of)
    for (const GhostMap::Pair& pair : ghosts.folds(grid.active_tiles()[t])) {
      // Each ghost has exactly one image, so this thread is the only one touching it: its values
      // are moved (not copied) to the image, and the ghost is left empty until the mirror.
      const std::size_t n = pair.node, m = pair.other;
      const auto& S = pair.sign;
      if (mass) {
        grid.mass[n] += grid.mass[m];
        // the body force on the ghost's share acts on the image with the factor S; the grid update
        // adds g to the image as an acceleration of the whole folded mass, so add (S - 1) m_g g
        for (int d = 0; d < 3; ++d) grid.force[d][n] += (S[d] - 1.0) * grid.mass[m] * gravity[d];
        grid.mass[m] = 0.0;
      }
      for (int d = 0; d < 3; ++d) {
        if (momentum) {
          grid.momentum[d][n] += S[d] * grid.momentum[d][m];
          grid.momentum[d][m] = 0.0;
        }
        if (force) {
          grid.force[d][n] += S[d] * grid.force[d][m];
          grid.force[d][m] = 0.0;
        }
      }
    }
  });
}

void add_mirror_ghost_nodes(TileStages& stages, Grid& grid, const GhostMap& ghosts, GhostFields fields) {
  if (ghosts.empty()) return;
  std::vector<NodeVectors*> targets;
  if (fields == GhostFields::AfterGridUpdate) targets = {&grid.momentum, &grid.force, &grid.velocity_l};
  if (fields == GhostFields::AfterGridUpdateForRemap) targets = {&grid.force, &grid.velocity_l};
  if (fields == GhostFields::Remapped) targets = {&grid.momentum};
  if (fields == GhostFields::Start) targets = {&grid.velocity_l};
  stages.add(TileReach::AnyTile, [&grid, &ghosts, targets](std::size_t t) {
    // the tile's ghost nodes in slot order, each with its interior image (Walls::mirror)
    for (const GhostMap::Pair& pair : ghosts.mirrors(grid.active_tiles()[t]))
      for (auto* field : targets)
        for (int d = 0; d < 3; ++d) (*field)[d][pair.node] = pair.sign[d] * (*field)[d][pair.other];
  });
}

}  // namespace talus
