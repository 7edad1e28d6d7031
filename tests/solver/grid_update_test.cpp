// The grid phase (solver/grid_update.hpp) on single nodes: v = p / m, v^L = v + (f / m + g) dt
// (Edo & Matsubara 2015, eq. 48-49), the named views of the reused arrays, empty nodes, the walls,
// and the friction work it returns.
#include "talus/solver/grid_update.hpp"

#include <gtest/gtest.h>

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

}  // namespace
}  // namespace grid_update_test
}  // namespace talus
