// The grid phase (solver/grid_update.hpp) on single nodes: v = p / m, v^L = v + (f / m + g) dt
// (Edo & Matsubara 2015, eq. 48-49), the named views of the reused arrays, empty nodes, the walls,
// and the friction work it returns; and the ghost nodes' fold and mirror around each node phase,
// against the same operations done one after the other.
#include "talus/solver/grid_update.hpp"

#include <gtest/gtest.h>
#include <omp.h>

#include <cstring>
#include <random>
#include <utility>

namespace talus {
namespace grid_update_test {
namespace {

struct OneTileGrid {
  Grid grid;
  Walls walls;
  std::size_t n = 0;  // a node on the z- face
  std::size_t inner = 0;
  explicit OneTileGrid(WallType floor, double mu = 0.0) {
    GridGeometry g;
    g.h = 0.1;
    g.cells = {4, 4, 4};
    grid = Grid(g);
    std::array<std::array<WallSpec, 2>, 3> specs{};
    for (auto& axis : specs)
      for (auto& side : axis) side.type = WallType::Open;
    specs[2][0] = {floor, mu};
    walls = Walls(specs, g);
    n = grid.node(kPad + 1, kPad + 1, kPad);
    inner = grid.node(kPad + 1, kPad + 1, kPad + 1);
    // the tile that holds both nodes (node (4..7, 4..7, 0..3) is tile (1, 1, 0) with kPad = 2)
    grid.set_active_tiles({static_cast<std::uint32_t>(n / kTileNodes)});
    grid.clear_active();
  }
  void set(std::size_t node, double m, Vec3 momentum, Vec3 force) {
    grid.mass[node] = m;
    for (int d = 0; d < 3; ++d) {
      grid.momentum[d][node] = momentum[d];
      grid.force[d][node] = force[d];
    }
  }
};

TEST(GridUpdate, VelocitiesFromMomentumAndForce) {
  OneTileGrid t(WallType::Open);
  ASSERT_EQ(t.n / kTileNodes, t.inner / kTileNodes);
  t.set(t.inner, 2.0, Vec3(1.0, -2.0, 4.0), Vec3(0.5, 0.0, -1.0));
  const Vec3 g(0.0, 0.0, -10.0);
  const double dt = 0.01;
  EXPECT_EQ(update_grid(t.grid, t.walls, g, dt, 1e-12), 0.0);
  const NodeVectors v = t.grid.velocity(), dv = t.grid.velocity_change(), vl = t.grid.lagrangian_velocity();
  const double expect_v[3] = {0.5, -1.0, 2.0};
  const double expect_vl[3] = {0.5 + 0.25 * dt, -1.0, 2.0 + (-0.5 - 10.0) * dt};
  for (int d = 0; d < 3; ++d) {
    EXPECT_DOUBLE_EQ(v[d][t.inner], expect_v[d]);
    EXPECT_DOUBLE_EQ(vl[d][t.inner], expect_vl[d]);
    EXPECT_DOUBLE_EQ(dv[d][t.inner], expect_vl[d] - expect_v[d]);
  }
}

TEST(GridUpdate, NodesBelowTheMassFloorAreEmpty) {
  OneTileGrid t(WallType::Open);
  t.set(t.inner, 1e-15, Vec3(1.0, 1.0, 1.0), Vec3(1.0, 1.0, 1.0));  // a huge p/m and f/m
  update_grid(t.grid, t.walls, Vec3(0, 0, -10), 0.01, 1e-12);
  for (int d = 0; d < 3; ++d) {
    EXPECT_EQ(t.grid.velocity()[d][t.inner], 0.0);
    EXPECT_EQ(t.grid.lagrangian_velocity()[d][t.inner], 0.0);
  }
}

TEST(GridUpdate, AFrictionalFloorStopsTheFallAndReturnsTheFrictionWork) {
  OneTileGrid t(WallType::Friction, 0.5);
  // A node on the floor sliding at 1 m/s along x and falling at 1 m/s.
  t.set(t.n, 1.0, Vec3(1.0, 0.0, -1.0), Vec3(0.0, 0.0, 0.0));
  const double work = update_grid(t.grid, t.walls, Vec3(0, 0, 0), 0.01, 1e-12);
  const NodeVectors vl = t.grid.lagrangian_velocity();
  EXPECT_EQ(vl[2][t.n], 0.0);                 // no rebound
  EXPECT_DOUBLE_EQ(vl[0][t.n], 0.5);          // 1 - mu |v_n|
  EXPECT_DOUBLE_EQ(work, 1.0 * 0.5 * 1.0);    // -J_t . v_start,t = m (1 - 0.5) * 1
  EXPECT_DOUBLE_EQ(t.grid.velocity_change()[0][t.n], -0.5);
}

// ---- The ghost nodes' fold and mirror in the node phase's loop (grid_update.hpp) --------------------

/// A grid with mirrored walls on several faces (slip and fixed, so their edges and corners hold
/// ghosts of ghosts' combinations) and a frictional floor, every node of every tile (inactive ones
/// too: stale values) holding random fields, a fifth of them below the mass floor.
struct WalledGrid {
  GridGeometry geometry;
  Grid grid;
  Walls walls;
  explicit WalledGrid(unsigned seed) {
    geometry.h = 0.1;
    geometry.cells = {9, 6, 5};
    grid = Grid(geometry);
    std::array<std::array<WallSpec, 2>, 3> specs{};
    specs[0] = {WallSpec{WallType::Slip, 0.0}, WallSpec{WallType::Fixed, 0.0}};
    specs[1] = {WallSpec{WallType::Slip, 0.0}, WallSpec{WallType::Open, 0.0}};
    specs[2] = {WallSpec{WallType::Friction, 0.4}, WallSpec{WallType::Slip, 0.0}};
    walls = Walls(specs, geometry);
    std::mt19937_64 rng(seed);
    std::uniform_real_distribution<double> u(-1.0, 1.0);
    const std::size_t nodes = grid.tile_count() * kTileNodes;
    for (std::size_t n = 0; n < nodes; ++n) {
      grid.mass[n] = u(rng) < -0.6 ? 0.0 : 1.5 + u(rng);
      for (int d = 0; d < 3; ++d) {
        grid.momentum[d][n] = u(rng);
        grid.force[d][n] = u(rng);
        grid.velocity_l[d][n] = u(rng);
      }
    }
  }
  /// Every double of every node record and v^L record, for a bitwise comparison.
  std::vector<double> fields() const {
    const std::size_t nodes = grid.tile_count() * kTileNodes;
    std::vector<double> all(grid.records(), grid.records() + nodes * kNodeRecord);
    all.insert(all.end(), grid.lagrangian_records(), grid.lagrangian_records() + nodes * kLagrangianRecord);
    return all;
  }
};

/// The fold done on its own, node by node from Walls (not GhostMap): each active tile's nodes take
/// the fields of their ghosts on active tiles (grid_update.hpp).
void fold_separately(WalledGrid& w, ScatteredFields f, const Vec3& g) {
  Grid& grid = w.grid;
  for (std::uint32_t tile : grid.active_tiles())
    for (int s = 0; s < kTileNodes; ++s) {
      const std::array<int, 3> node = Grid::node_in_tile(grid.node_of(tile), s);
      const std::size_t image = static_cast<std::size_t>(tile) * kTileNodes + s;
      Walls::GhostNodes ghosts;
      Walls::GhostSigns signs;
      for (int k = 0, count = w.walls.ghosts_of(node, ghosts, signs); k < count; ++k) {
        const std::size_t ghost = grid.node(ghosts[k][0], ghosts[k][1], ghosts[k][2]);
        if (!grid.tile_active(ghost / kTileNodes)) continue;  // no particle reached it: it holds no sums
        if (f.mass) {
          grid.mass[image] += grid.mass[ghost];
          for (int d = 0; d < 3; ++d) grid.force[d][image] += (signs[k][d] - 1.0) * grid.mass[ghost] * g[d];
          grid.mass[ghost] = 0.0;
        }
        for (int d = 0; d < 3; ++d) {
          if (f.momentum) grid.momentum[d][image] += signs[k][d] * std::exchange(grid.momentum[d][ghost], 0.0);
          if (f.force) grid.force[d][image] += signs[k][d] * std::exchange(grid.force[d][ghost], 0.0);
        }
      }
    }
}

/// The mirror done on its own: each ghost node of an active tile takes its image's reflection.
void mirror_separately(WalledGrid& w, std::vector<NodeVectors*> fields) {
  Grid& grid = w.grid;
  for (std::uint32_t tile : grid.active_tiles())
    for (int s = 0; s < kTileNodes; ++s) {
      std::array<int, 3> image;
      std::array<double, 3> sign;
      if (!w.walls.mirror(Grid::node_in_tile(grid.node_of(tile), s), image, sign)) continue;
      const std::size_t ghost = static_cast<std::size_t>(tile) * kTileNodes + s;
      for (auto* field : fields)
        for (int d = 0; d < 3; ++d) (*field)[d][ghost] = sign[d] * (*field)[d][grid.node(image[0], image[1], image[2])];
    }
}

enum class Phase { GridUpdate, GridUpdateForRemap, Remap, Start };

/// Runs `phase` on w's active tiles: with the ghost map (one stage) or, with `separately`, as the
/// fold, the phase without ghosts and the mirror one after the other. Returns the wall work.
double run_phase(WalledGrid& w, Phase phase, bool separately, int threads) {
  const Vec3 g(1.0, -2.0, -9.81);
  const double floor = 1e-3, dt = 0.01;
  GhostMap map(w.walls, w.grid);
  map.list_active_tiles(w.walls, w.grid);
  const GhostMap none;
  const GhostMap& ghosts = separately ? none : map;
  const ScatteredFields fold = phase == Phase::Remap   ? ScatteredFields{.momentum = true}
                               : phase == Phase::Start ? ScatteredFields{.mass = true, .momentum = true}
                                                       : ScatteredFields{.mass = true, .momentum = true, .force = true};
  if (separately) fold_separately(w, fold, g);
  TileStages stages(w.grid.active_tiles().size());
  std::vector<double> tile_work;
  Grid& grid = w.grid;
  switch (phase) {
    case Phase::GridUpdate:
    case Phase::GridUpdateForRemap:
      add_grid_update(stages, grid, w.walls, ghosts, fold, g, dt, floor, phase == Phase::GridUpdateForRemap, tile_work);
      break;
    case Phase::Remap: add_velocities_from_momentum(stages, grid, w.walls, ghosts, g, floor); break;
    case Phase::Start: add_start_velocities(stages, grid, w.walls, ghosts, g, floor); break;
  }
  const int before = omp_get_max_threads();
  omp_set_num_threads(threads);
  stages.run();
  omp_set_num_threads(before);
  if (separately) {
    switch (phase) {
      case Phase::GridUpdate: mirror_separately(w, {&grid.momentum, &grid.force, &grid.velocity_l}); break;
      case Phase::GridUpdateForRemap: mirror_separately(w, {&grid.force, &grid.velocity_l}); break;
      case Phase::Remap: mirror_separately(w, {&grid.momentum}); break;
      case Phase::Start: mirror_separately(w, {&grid.velocity_l}); break;
    }
  }
  return counted_work(tile_work);
}

TEST(GhostPhase, IsTheFoldThePhaseAndTheMirrorOneAfterTheOther) {
  // Active sets: every tile; and tiles left out at random, so that ghosts and images fall on
  // active and inactive tiles in every combination (a ghost whose image is inactive copies it
  // stale; an inactive ghost is neither folded nor mirrored: what it holds is stale).
  WalledGrid probe(0);
  const std::size_t tiles = probe.grid.tile_count();
  for (unsigned set = 0; set < 4; ++set) {
    std::vector<std::uint32_t> active;
    std::mt19937 pick(set);
    for (std::uint32_t t = 0; t < tiles; ++t)
      if (set == 0 || pick() % 3 != 0) active.push_back(t);
    for (Phase phase : {Phase::GridUpdate, Phase::GridUpdateForRemap, Phase::Remap, Phase::Start}) {
      WalledGrid reference(set + 1), fused(set + 1), fused_threads(set + 1);
      for (WalledGrid* w : {&reference, &fused, &fused_threads}) w->grid.set_active_tiles(active);
      const double work_reference = run_phase(reference, phase, true, 1);
      EXPECT_EQ(run_phase(fused, phase, false, 1), work_reference);
      EXPECT_EQ(run_phase(fused_threads, phase, false, 5), work_reference);
      const std::vector<double> expected = reference.fields(), got = fused.fields(), got_threads = fused_threads.fields();
      ASSERT_EQ(got.size(), expected.size());
      EXPECT_EQ(std::memcmp(got.data(), expected.data(), expected.size() * sizeof(double)), 0)
          << "active set " << set << ", phase " << static_cast<int>(phase);
      EXPECT_EQ(std::memcmp(got_threads.data(), expected.data(), expected.size() * sizeof(double)), 0)
          << "active set " << set << ", phase " << static_cast<int>(phase) << ", 5 threads";
    }
  }
}

}  // namespace
}  // namespace grid_update_test
}  // namespace talus
