// TerrainProfile: heights, slopes, normals and arc length of a piecewise-linear bed with circular
// transitions, against closed-form geometry.
#include "talus/core/error.hpp"
#include "talus/grid/terrain_profile.hpp"

#include <gtest/gtest.h>

#include <cmath>

namespace talus {
namespace terrain_profile_test {
namespace {

constexpr double kPi = 3.14159265358979323846;

// A flume: a 30-degree slope 1 m long (along the bed) down to (0, 0), then a flat runout to x = 1,
// with a 0.2 m radius transition at the vertex.
TerrainProfile flume(double radius) {
  const double t = 30.0 * kPi / 180.0;
  TerrainSpec spec;
  spec.points = {{-std::cos(t), std::sin(t)}, {0.0, 0.0}, {1.0, 0.0}};
  spec.radii = {0.0, radius, 0.0};
  return TerrainProfile(spec);
}

TEST(TerrainProfile, SharpKinkIsPiecewiseLinearWithArcLengthAlongTheBed) {
  const TerrainProfile p = flume(0.0);
  const double t = 30.0 * kPi / 180.0;
  EXPECT_NEAR(p.height(-0.5), 0.5 * std::tan(t), 1e-14);
  EXPECT_NEAR(p.slope(-0.5), -std::tan(t), 1e-14);
  EXPECT_NEAR(p.height(0.5), 0.0, 1e-14);
  EXPECT_NEAR(p.slope(0.5), 0.0, 1e-14);
  ASSERT_EQ(p.kinks().size(), 1u);
  EXPECT_NEAR(p.kinks()[0], 0.0, 1e-14);
  EXPECT_NEAR(p.arc_length(0.0), 1.0, 1e-14);  // the slope is 1 m long
  EXPECT_NEAR(p.arc_length(1.0), 2.0, 1e-14);
  EXPECT_NEAR(p.arc_length(2.0), 3.0, 1e-14);  // the last segment continues straight
  EXPECT_NEAR(p.arc_length(-std::cos(t) - std::cos(t)), -1.0, 1e-14);  // and so does the first
  for (double s : {-0.5, 0.3, 1.0, 1.7, 2.5}) EXPECT_NEAR(p.arc_length(p.x_at_arc_length(s)), s, 1e-13) << s;
  const Vec3 n = p.normal(-0.5);
  EXPECT_NEAR(n.norm(), 1.0, 1e-14);
  EXPECT_NEAR(n[0], std::sin(t), 1e-14);  // the normal of a bed falling towards +x leans towards +x
  EXPECT_NEAR(n[2], std::cos(t), 1e-14);
}

TEST(TerrainProfile, CircularTransitionIsTangentToBothSegments) {
  const double r = 0.2, t = 30.0 * kPi / 180.0;
  const TerrainProfile p = flume(r);
  EXPECT_TRUE(p.kinks().empty());
  const double T = r * std::tan(0.5 * t);  // tangent length
  const double xa = -T * std::cos(t), xb = T;
  // continuous height and slope at both tangent points
  for (double x : {xa, xb}) {
    EXPECT_NEAR(p.height(x - 1e-9), p.height(x + 1e-9), 1e-8) << x;
    EXPECT_NEAR(p.slope(x - 1e-9), p.slope(x + 1e-9), 1e-6) << x;
  }
  EXPECT_NEAR(p.slope(xa + 1e-12), -std::tan(t), 1e-6);
  EXPECT_NEAR(p.slope(xb - 1e-12), 0.0, 1e-6);
  // the arc's lowest point is the tangent point on the runout; the centre is (xb, r)
  const double xm = 0.5 * (xa + xb);
  EXPECT_NEAR(std::hypot(xm - xb, p.height(xm) - r), r, 1e-13);
  // the arc is shorter than the two tangent lengths it replaces by 2T - r*theta
  EXPECT_NEAR(p.arc_length(1.0), 2.0 - (2.0 * T - r * t), 1e-13);
  for (double s : {0.9, 1.0, 1.05, 1.2}) EXPECT_NEAR(p.arc_length(p.x_at_arc_length(s)), s, 1e-12) << s;
  const auto range = p.height_range(-0.5, 0.5);
  EXPECT_NEAR(range[0], 0.0, 1e-14);
  EXPECT_NEAR(range[1], 0.5 * std::tan(t), 1e-14);
}

TEST(TerrainProfile, ConcaveDownTransitionBulgesUp) {
  TerrainSpec spec;
  spec.points = {{0.0, 0.0}, {1.0, 0.0}, {2.0, -1.0}};  // flat, then down at 45 degrees
  spec.radii = {0.0, 0.5, 0.0};
  const TerrainProfile p(spec);
  const double T = 0.5 * std::tan(kPi / 8.0);
  // the arc lies below the two lines it joins (inside the corner) and above the chord
  EXPECT_LT(p.height(1.0), 0.0);
  EXPECT_GT(p.height(1.0), -0.5 * T);
  EXPECT_NEAR(p.slope(1.0 - T + 1e-12), 0.0, 1e-6);
}

TEST(TerrainProfile, RefusesProfilesThatAreNotAGraph) {
  TerrainSpec spec;
  spec.points = {{0.0, 0.0}};
  EXPECT_THROW(TerrainProfile{spec}, Error);
  spec.points = {{0.0, 0.0}, {0.0, 1.0}};
  EXPECT_THROW(TerrainProfile{spec}, Error);
  spec.points = {{0.0, 1.0}, {1.0, 0.0}, {1.2, 0.0}};
  spec.radii = {0.0, 5.0, 0.0};  // transition longer than the segments
  EXPECT_THROW(TerrainProfile{spec}, Error);
  spec.radii = {0.0, -1.0, 0.0};
  EXPECT_THROW(TerrainProfile{spec}, Error);
}

// A transition too long for its segment is refused with the segment's length, what it takes, and the
// largest radius that fits (it named the points, one without a transition, and no range).
TEST(TerrainProfile, ATransitionTooLongForItsSegmentNamesTheLargestRadius) {
  TerrainSpec spec;
  spec.points = {{0.0, 1.0}, {1.0, 0.0}, {1.2, 0.0}, {3.0, 1.0}};
  spec.radii = {0.0, 5.0, 0.0, 0.0};  // a 45-degree turn: tangent length 5 tan(22.5 deg) = 2.07 m; the first segment is 1.41 m
  try {
    TerrainProfile{spec};
    FAIL() << "accepted";
  } catch (const Error& e) {
    EXPECT_EQ(std::string(e.what()),
              "radii: the transitions do not fit on the 1.414 m segment from point 0 to point 1 (radii[1] = 5 takes "
              "2.071 m): allowed radii[1] <= 3.414");
  }
  spec.radii = {0.0, 0.4828, 0.0, 0.0};  // what the 0.2 m segment after it allows (0.2 / tan 22.5 deg), to 4 digits: fits
  EXPECT_NO_THROW(TerrainProfile{spec});
  spec.radii = {0.0, 0.3, 0.3, 0.0};  // two transitions on the 0.2 m segment: 0.124 + 0.078 m; each bound with the other's as given
  try {
    TerrainProfile{spec};
    FAIL() << "accepted";
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find("allowed radii[1] <= "), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find(" or radii[2] <= "), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find("(each with the other's as given)"), std::string::npos) << e.what();
  }
}

}  // namespace
}  // namespace terrain_profile_test
}  // namespace talus
