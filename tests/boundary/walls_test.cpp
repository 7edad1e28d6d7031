// Walls (boundary/walls.hpp): the rules for fixed, slip, open and frictional walls at the three
// stages of a step, on a node velocity, with the contact rule of Abe, Johansson & Konagai 2005
// (eq. 14-18): a node moving into the wall is in contact, loses its normal velocity (no rebound),
// and Coulomb friction reduces its tangential velocity by at most mu |dv_n|.
#include "talus/boundary/walls.hpp"

#include <gtest/gtest.h>

#include <cmath>

namespace talus {
namespace walls_test {
namespace {

GridGeometry box() {
  GridGeometry g;
  g.h = 0.1;
  g.cells = {4, 4, 4};
  return g;
}

/// Walls with `floor` on z- and every other face open.
Walls walls_with_floor(WallSpec floor) {
  std::array<std::array<WallSpec, 2>, 3> specs{};
  for (auto& axis : specs)
    for (auto& side : axis) side.type = WallType::Open;
  specs[2][0] = floor;
  return Walls(specs, box());
}

const std::array<int, 3> kFloorNode{kPad + 2, kPad + 2, kPad};     // on the z- face
const std::array<int, 3> kInnerNode{kPad + 2, kPad + 2, kPad + 1};  // one node above it

TEST(Walls, OnlyNodesOnAWallFaceAreTouched) {
  const Walls walls = walls_with_floor({WallType::Slip, 0.0});
  EXPECT_TRUE(walls.touches(kFloorNode));
  EXPECT_TRUE(walls.touches({kPad + 2, kPad + 2, kPad - 1}));  // a ghost node below the face
  EXPECT_FALSE(walls.touches(kInnerNode));
  double v[3] = {1.0, 2.0, -3.0};
  walls.apply(kInnerNode, v, Walls::Stage::GridUpdate);
  EXPECT_EQ(v[2], -3.0);
}

TEST(Walls, FixedSlipAndOpen) {
  double v[3] = {1.0, 2.0, -3.0};
  walls_with_floor({WallType::Fixed, 0.0}).apply(kFloorNode, v, Walls::Stage::GridUpdate);
  EXPECT_EQ(v[0], 0.0);
  EXPECT_EQ(v[1], 0.0);
  EXPECT_EQ(v[2], 0.0);
  double w[3] = {1.0, 2.0, 3.0};  // a slip wall holds the normal velocity both ways
  walls_with_floor({WallType::Slip, 0.0}).apply(kFloorNode, w, Walls::Stage::GridUpdate);
  EXPECT_EQ(w[0], 1.0);
  EXPECT_EQ(w[1], 2.0);
  EXPECT_EQ(w[2], 0.0);
}

TEST(Walls, CoulombFrictionSlidesSlowerOrSticksAndCountsItsWork) {
  const Walls walls = walls_with_floor({WallType::Friction, 0.3});
  // Into the floor at 1 m/s with 0.5 m/s along x: slides, 0.5 - 0.3 * 1 = 0.2 m/s left.
  double v[3] = {0.5, 0.0, -1.0};
  const double m = 2.0, v_start[3] = {0.4, 0.0, -0.5};
  const double work = walls.apply(kFloorNode, v, Walls::Stage::GridUpdate, m, v_start);
  EXPECT_EQ(v[2], 0.0);
  EXPECT_NEAR(v[0], 0.2, 1e-15);
  EXPECT_NEAR(work, m * 0.3 * v_start[0], 1e-15);  // -J_t . v_start,t with J_t = m (0.2 - 0.5)
  // A tangential speed below mu |v_n| sticks.
  double s[3] = {0.1, 0.2, -1.0};
  walls.apply(kFloorNode, s, Walls::Stage::GridUpdate, m, v_start);
  EXPECT_EQ(s[0], 0.0);
  EXPECT_EQ(s[1], 0.0);
  EXPECT_EQ(s[2], 0.0);
  // Separating from the floor: free, no work.
  double up[3] = {0.5, 0.0, 1.0};
  EXPECT_EQ(walls.apply(kFloorNode, up, Walls::Stage::GridUpdate, m, v_start), 0.0);
  EXPECT_EQ(up[0], 0.5);
  EXPECT_EQ(up[2], 1.0);
}

TEST(Walls, TheRemapKeepsTheGridUpdatesContactAndStartTouches) {
  const Walls walls = walls_with_floor({WallType::Friction, 0.3});
  // A node held by the floor in the grid update (v^L . n = 0) has no normal velocity in the remap
  // either, even if the remapped momentum points away; friction is not applied twice.
  const double held[3] = {0.2, 0.0, 0.0};
  double remapped[3] = {0.5, 0.0, 0.7};
  walls.apply(kFloorNode, remapped, Walls::Stage::Remap, 0.0, nullptr, held);
  EXPECT_EQ(remapped[2], 0.0);
  EXPECT_EQ(remapped[0], 0.5);
  // A node that separated in the grid update stays free in the remap.
  const double separated[3] = {0.2, 0.0, 0.4};
  double free[3] = {0.5, 0.0, 0.7};
  walls.apply(kFloorNode, free, Walls::Stage::Remap, 0.0, nullptr, separated);
  EXPECT_EQ(free[2], 0.7);
  // USF / USAVG start velocities: a wall node is treated as touching.
  double start[3] = {0.5, 0.0, 0.7};
  walls.apply(kFloorNode, start, Walls::Stage::Start);
  EXPECT_EQ(start[2], 0.0);
  EXPECT_EQ(start[0], 0.5);
}

TEST(Walls, ABedAlongZOnATerrainGridActsLikeTheFlatFloor) {
  // A terrain grid whose bed is flat: the z- face is the bed, with normal (0, 0, 1) at every column.
  GridGeometry g = box();
  g.terrain.points = {{-1.0, 0.0}, {2.0, 0.0}};
  const ProfileTerrain bed = grid_bed(g);
  std::array<std::array<WallSpec, 2>, 3> specs{};
  for (auto& axis : specs)
    for (auto& side : axis) side.type = WallType::Open;
  specs[2][0] = {WallType::Friction, 0.3};
  const Walls terrain(specs, g, bed);
  const Walls flat = walls_with_floor({WallType::Friction, 0.3});
  for (const Walls::Stage stage : {Walls::Stage::GridUpdate, Walls::Stage::Remap, Walls::Stage::Start}) {
    const double contact[3] = {0.1, 0.0, 0.0}, v_start[3] = {0.3, -0.1, -0.2};
    double a[3] = {0.5, -0.2, -1.0}, b[3] = {0.5, -0.2, -1.0};
    const double wa = terrain.apply(kFloorNode, a, stage, 1.5, v_start, contact);
    const double wb = flat.apply(kFloorNode, b, stage, 1.5, v_start, contact);
    for (int d = 0; d < 3; ++d) EXPECT_NEAR(a[d], b[d], 1e-15) << int(stage);
    EXPECT_NEAR(wa, wb, 1e-15);
  }
}

}  // namespace
}  // namespace walls_test
}  // namespace talus
