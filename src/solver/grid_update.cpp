#include "talus/solver/grid_update.hpp"

#include <array>
#include <vector>

namespace talus {

namespace {

/// node_update(n, node) on every node of active tile t but the slots set in `skip`, in slot order
/// (n: the node's index, node: its (i, j, k)); returns the sum of what it returns (the tile's energy).
/// (Inlined into the stage, as the loops were before the ghosts' skip: out of line, the remap's
/// velocities took a third longer.)
template <class NodeUpdate>
[[gnu::always_inline]] inline double for_tile_nodes(const Grid& grid, std::size_t t, std::uint64_t skip,
                                                    NodeUpdate&& node_update) {
  const std::uint32_t tile = grid.active_tiles()[t];
  const std::size_t begin = static_cast<std::size_t>(tile) * kTileNodes;
  const std::array<int, 3> first = grid.node_of(tile);
  double energy = 0.0;
  if (skip == 0) {
    for (int s = 0; s < kTileNodes; ++s) energy += node_update(begin + s, Grid::node_in_tile(first, s));
  } else {
    for (int s = 0; s < kTileNodes; ++s)
      if (!((skip >> s) & 1u)) energy += node_update(begin + s, Grid::node_in_tile(first, s));
  }
  return energy;
}

/// The fields the mirror reflects (GhostFields).
std::vector<NodeVectors*> mirrored_fields(Grid& grid, GhostFields fields) {
  switch (fields) {
    case GhostFields::AfterGridUpdate: return {&grid.momentum, &grid.force, &grid.velocity_l};
    case GhostFields::AfterGridUpdateForRemap: return {&grid.force, &grid.velocity_l};
    case GhostFields::Remapped: return {&grid.momentum};
    case GhostFields::Start: return {&grid.velocity_l};
  }
  return {};
}

/// Active tile t's fold: the fields of each ghost whose image is one of t's nodes move to the image
/// (the header's comment before add_grid_update says what and why).
void fold_tile(Grid& grid, const GhostMap& ghosts, ScatteredFields fields, const Vec3& gravity, std::size_t t) {
  const auto [mass, momentum, force] = fields;
  // the tile's nodes in slot order, each with the ghosts whose image it is (Walls::ghosts_of)
  for (const GhostMap::Pair& pair : ghosts.folds(grid.active_tiles()[t])) {
    // Each ghost has exactly one image, so this thread is the only one touching it: its values
    // are moved (not copied) to the image, and the ghost is left empty until the mirror.
    const std::size_t n = pair.node, m = pair.other;
    // A ghost on an inactive tile holds nothing of this step: no particle reaches it, and the grid
    // clear skips it. What it may hold is the mirror of the last step in which its tile was active
    // (momentum, force, no mass): folded in, that momentum without its mass flung the image's
    // particles 1.1 cells in one step, at the first sort after the block moved off the wall.
    if (!grid.tile_active(m / kTileNodes)) continue;
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
}

/// Adds a node phase: per active tile, node_work(t, skip) over the tile's nodes but those in skip.
/// With mirrored walls, the phase folds the ghosts into their images first and mirrors them back
/// after, in one loop over the tiles (the header says how), and, only where an unfolded ghost's
/// image lies on another active tile, a second loop after a barrier that mirrors those.
template <class NodeWork>
void add_node_phase(TileStages& stages, Grid& grid, const GhostMap& ghosts, ScatteredFields fold, const Vec3& gravity,
                    GhostFields mirror, NodeWork node_work) {
  if (ghosts.empty()) {
    stages.add(TileReach::OwnTile, [node_work](std::size_t t) { node_work(t, 0); });
    return;
  }
  const std::vector<NodeVectors*> targets = mirrored_fields(grid, mirror);
  auto copy = [targets](const GhostMap::Pair& pair, std::size_t to, std::size_t from) {
    for (auto* field : targets)
      for (int d = 0; d < 3; ++d) (*field)[d][to] = pair.sign[d] * (*field)[d][from];
  };
  stages.add(TileReach::AnyTile, [&grid, &ghosts, fold, gravity, copy, node_work](std::size_t t) {
    const std::uint32_t tile = grid.active_tiles()[t];
    fold_tile(grid, ghosts, fold, gravity, t);
    // This tile's folded ghosts whose image is active belong to the image's tile in this phase: it
    // folded them (above, on its own thread) and mirrors them (below). Nothing here touches them.
    // The others are mirrored here after the node work, pulled from an image that nobody writes in
    // this loop: an inactive one, or an unfolded ghost's image on this tile (done on this thread).
    std::uint64_t skip = 0, pull = 0;
    const std::size_t first = static_cast<std::size_t>(tile) * kTileNodes;
    for (const GhostMap::Pair& pair : ghosts.mirrors(tile)) {
      const std::size_t image_tile = pair.other / kTileNodes;
      const bool image_active = grid.tile_active(image_tile);
      const std::uint64_t bit = std::uint64_t{1} << (pair.node - first);
      if (pair.folded && image_active) skip |= bit;
      if (!image_active || (!pair.folded && image_tile == tile)) pull |= bit;
    }
    node_work(t, skip);
    // The mirror of the ghosts this tile folded, pushed now that its nodes are done (an inactive
    // ghost gets none).
    for (const GhostMap::Pair& pair : ghosts.folds(tile))
      if (grid.tile_active(pair.other / kTileNodes)) copy(pair, pair.other, pair.node);
    if (pull)
      for (const GhostMap::Pair& pair : ghosts.mirrors(tile))
        if ((pull >> (pair.node - first)) & 1u) copy(pair, pair.node, pair.other);
  });
  if (!ghosts.mirrors_after_barrier()) return;
  // An unfolded ghost whose image is on another active tile: its node work ran on its own tile, the
  // image's on the image's, so the mirror waits for both. (Unfolded ghosts lie only in the tiles'
  // slack beyond the padded grid, which no particle reaches: they hold no mass.)
  stages.add(TileReach::AnyTile, [&grid, &ghosts, copy](std::size_t t) {
    const std::uint32_t tile = grid.active_tiles()[t];
    for (const GhostMap::Pair& pair : ghosts.mirrors(tile)) {
      const std::size_t image_tile = pair.other / kTileNodes;
      if (!pair.folded && image_tile != tile && grid.tile_active(image_tile)) copy(pair, pair.node, pair.other);
    }
  });
}

}  // namespace

void add_grid_update(TileStages& stages, Grid& grid, const Walls& walls, const GhostMap& ghosts, ScatteredFields fold,
                     const Vec3& gravity, double dt, double mass_floor, bool zero_momentum,
                     std::vector<double>& tile_work, std::vector<TileGapTerms>* tile_gap) {
  tile_work.assign(grid.active_tiles().size(), 0.0);
  if (tile_gap) tile_gap->assign(grid.active_tiles().size(), TileGapTerms{});
  const GhostFields mirror = zero_momentum ? GhostFields::AfterGridUpdateForRemap : GhostFields::AfterGridUpdate;
  add_node_phase(stages, grid, ghosts, fold, gravity, mirror,
                 [&grid, &walls, &tile_work, tile_gap, gravity, dt, mass_floor, zero_momentum](std::size_t t,
                                                                                               std::uint64_t skip) {
    TileGapTerms gap;
    tile_work[t] = for_tile_nodes(grid, t, skip, [&](std::size_t n, const std::array<int, 3>& node) {
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
      if (tile_gap) [[unlikely]] {
        // The grid's kinetic energy change 1/2 m (|v^L|^2 - |v|^2) = m (v^L - v) . v_mean, split
        // into the forces' work at v_mean and the walls' share (the rest); read before the force
        // slot is overwritten below.
        for (int d = 0; d < 3; ++d) {
          const double mean = 0.5 * (v[d] + vl[d]), dv = vl[d] - v[d];
          const double force_work = dt * record[kForceSlot + d] * mean, gravity_work = dt * m * gravity[d] * mean;
          gap.stress_work -= force_work;
          gap.gravity_work += gravity_work;
          gap.wall_work -= m * dv * mean - force_work - gravity_work;
          gap.increment_kinetic += 0.5 * m * dv * dv;
        }
      }
      for (int d = 0; d < 3; ++d) {
        record[kMomentumSlot + d] = zero_momentum ? 0.0 : v[d];
        record[kForceSlot + d] = vl[d] - v[d];
        lagrangian[d] = vl[d];
      }
      return removed;
    });
    if (tile_gap) (*tile_gap)[t] = gap;
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
  add_grid_update(stages, grid, walls, GhostMap(), {}, gravity, dt, mass_floor, zero_momentum, tile_work);
  stages.run();
  return counted_work(tile_work, counted);
}

namespace {

/// v = momentum / m with the walls at `stage`, written into `target` (zero on empty nodes), as a node
/// phase with the ghosts' fold of `fold` and their mirror of `mirror`. For the remap, `velocity_l`
/// still holds this step's v^L: the contact state of the grid update.
void add_wall_projected_velocities(TileStages& stages, Grid& grid, const Walls& walls, const GhostMap& ghosts,
                                   ScatteredFields fold, GhostFields mirror, const Vec3& gravity, double mass_floor,
                                   Walls::Stage stage, NodeVectors& target) {
  add_node_phase(stages, grid, ghosts, fold, gravity, mirror,
                 [&grid, &walls, &target, mass_floor, stage](std::size_t t, std::uint64_t skip) {
    for_tile_nodes(grid, t, skip, [&](std::size_t n, const std::array<int, 3>& node) {
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

void add_velocities_from_momentum(TileStages& stages, Grid& grid, const Walls& walls, const GhostMap& ghosts,
                                  const Vec3& gravity, double mass_floor) {
  add_wall_projected_velocities(stages, grid, walls, ghosts, {.momentum = true}, GhostFields::Remapped, gravity,
                                mass_floor, Walls::Stage::Remap, grid.momentum);
}

void add_start_velocities(TileStages& stages, Grid& grid, const Walls& walls, const GhostMap& ghosts,
                          const Vec3& gravity, double mass_floor) {
  add_wall_projected_velocities(stages, grid, walls, ghosts, {.mass = true, .momentum = true}, GhostFields::Start,
                                gravity, mass_floor, Walls::Stage::Start, grid.velocity_l);
}

}  // namespace talus
