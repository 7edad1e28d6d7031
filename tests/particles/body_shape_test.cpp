// Body shapes (scene bodies[i].box / .prism): the polygon tests, the prism's validation messages,
// and seeding that keeps exactly the candidate points inside the prism.
#include "../solver/scene_fixtures.hpp"
#include "talus/core/error.hpp"
#include "talus/core/polygon.hpp"
#include "talus/particles/body_shape.hpp"
#include "talus/particles/seeding.hpp"
#include "talus/scene/scene_json.hpp"

#include <fmt/core.h>
#include <gtest/gtest.h>

#include <cmath>

namespace talus {
namespace body_shape_test {
namespace {

const PolygonPoints kSquare = {{0, 0}, {1, 0}, {1, 1}, {0, 1}};
// An L shape (non-convex): the unit square [0, 2] x [0, 2] without its upper-right quarter.
const PolygonPoints kEll = {{0, 0}, {2, 0}, {2, 1}, {1, 1}, {1, 2}, {0, 2}};

TEST(Polygon, ContainsInsideNotOutsideOfANonConvexShape) {
  EXPECT_TRUE(polygon_contains(kEll, 0.5, 0.5));
  EXPECT_TRUE(polygon_contains(kEll, 1.5, 0.5));
  EXPECT_TRUE(polygon_contains(kEll, 0.5, 1.5));
  EXPECT_FALSE(polygon_contains(kEll, 1.5, 1.5));  // the missing quarter
  EXPECT_FALSE(polygon_contains(kEll, -0.1, 0.5));
  EXPECT_FALSE(polygon_contains(kEll, 2.5, 0.5));
  // Clockwise vertex order gives the same answers.
  const PolygonPoints reversed(kEll.rbegin(), kEll.rend());
  EXPECT_TRUE(polygon_contains(reversed, 1.5, 0.5));
  EXPECT_FALSE(polygon_contains(reversed, 1.5, 1.5));
}

TEST(Polygon, SharedEdgeBelongsToExactlyOneOfTwoNeighbours) {
  const PolygonPoints right = {{1, 0}, {2, 0}, {2, 1}, {1, 1}};
  for (double v : {0.0, 0.25, 0.5, 0.999}) {
    EXPECT_NE(polygon_contains(kSquare, 1.0, v), polygon_contains(right, 1.0, v)) << "x = 1, z = " << v;
  }
  const PolygonPoints above = {{0, 1}, {1, 1}, {1, 2}, {0, 2}};
  EXPECT_NE(polygon_contains(kSquare, 0.5, 1.0), polygon_contains(above, 0.5, 1.0));
}

TEST(Polygon, SignedAreaByOrientation) {
  EXPECT_DOUBLE_EQ(polygon_signed_area(kSquare), 1.0);
  EXPECT_DOUBLE_EQ(polygon_signed_area(kEll), 3.0);
  const PolygonPoints reversed(kEll.rbegin(), kEll.rend());
  EXPECT_DOUBLE_EQ(polygon_signed_area(reversed), -3.0);
}

TEST(Polygon, CrossingEdgesFoundInBowtiesRepeatsAndFoldBacks) {
  EXPECT_EQ(polygon_crossing_edges(kSquare)[0], -1);
  EXPECT_EQ(polygon_crossing_edges(kEll)[0], -1);
  const PolygonPoints bowtie = {{0, 0}, {1, 1}, {1, 0}, {0, 1}};
  EXPECT_EQ(polygon_crossing_edges(bowtie), (std::array<int, 2>{0, 2}));
  const PolygonPoints repeated = {{0, 0}, {1, 0}, {1, 0}, {0, 1}};
  EXPECT_GE(polygon_crossing_edges(repeated)[0], 0);
  const PolygonPoints fold_back = {{0, 0}, {2, 0}, {1, 0}, {0, 1}};  // edge 1 runs back over edge 0
  EXPECT_GE(polygon_crossing_edges(fold_back)[0], 0);
  const PolygonPoints touching = {{0, 0}, {2, 0}, {2, 2}, {1, 0}, {0, 2}};  // vertex 3 lies on edge 0
  EXPECT_GE(polygon_crossing_edges(touching)[0], 0);
}

std::string prism_scene(const std::string& prism, double cell = 0.1, int n = 2) {
  return fmt::format(R"({{
    "grid": {{ "size": [1, 1, 1], "cell_size": {} }},
    "time": {{ "end": 0.1 }},
    "materials": {{ "m": {{ "density": 1000, "young": 1e6, "poisson": 0.3 }} }},
    "bodies": [ {{ "name": "wedge", "material": "m", "prism": {}, "particles_per_cell": {} }} ]
  }})", cell, prism, n);
}

std::string error_of(const std::string& text) { return test::scene_error_of(text, test::SceneStage::ReadAndSeed); }

TEST(PrismBody, BadPrismsAreRefusedNamingTheKey) {
  auto has = [](const std::string& what, const char* part) { return what.find(part) != std::string::npos; };
  // (the prism's JSON, a part of the error it must give)
  const std::pair<const char*, const char*> cases[] = {
      {R"({"points": [[0.1, 0.1], [0.5, 0.1]], "y": [0.2, 0.8]})", "bodies[0].prism.points must be an array of at least 3"},
      {R"({"points": [[0.1, 0.1], [0.5, 0.5], [0.5, 0.1], [0.1, 0.5]], "y": [0.2, 0.8]})", "bodies[0].prism.points is not a simple polygon: edge 0"},
      {R"({"points": [[0.1, 0.1], [0.3, 0.3], [0.5, 0.5]], "y": [0.2, 0.8]})", "bodies[0].prism.points"},  // collinear: folds back on itself
      // a ring closed as GIS tools write it: it said "edge 0 (points 0 to 1) touches edge 2 (points 2 to 3)"
      {R"({"points": [[0.1, 0.1], [0.5, 0.1], [0.3, 0.5], [0.1, 0.1]], "y": [0.2, 0.8]})",
       "bodies[0].prism.points: the last point, [0.1, 0.1], repeats the first; leave it out"},
      {R"({"points": [[0.1, 0.1], [0.5, 0.1], [0.5, "a"]], "y": [0.2, 0.8]})", "bodies[0].prism.points[2][1] must be a finite number"},
      {R"({"points": [[0.1, 0.1], [0.5, 0.1], [0.5, 0.5]], "y": [0.8, 0.2]})", "bodies[0].prism.y = [0.8, 0.2] must have y0 < y1"},
      {R"({"points": [[0.1, 0.1], [1.5, 0.1], [0.5, 0.5]], "y": [0.2, 0.8]})", "bodies[0].prism [0.1, 1.5] along axis 0 lies partly outside the grid"},
      {R"({"points": [[0.1, 0.1], [0.5, 0.1], [0.5, 0.5]], "y": [0.2, 0.8], "z": 1})", "unknown key bodies[0].prism.z"},
      // A sliver between the particle rows holds no particle: refused when seeded, naming the prism.
      {R"({"points": [[0.1, 0.01], [0.9, 0.01], [0.9, 0.02]], "y": [0.2, 0.8]})", "bodies[0].prism (\"wedge\") holds no particle"},
      // A diagonal sliver whose bounding box spans many particle points, none of them inside.
      {R"({"points": [[0.0, 0.01], [0.9, 0.91], [0.9, 0.912]], "y": [0.2, 0.8]})", "bodies[0].prism (\"wedge\") holds no particle: no particle point"},
  };
  for (const auto& [prism, part] : cases) {
    const std::string e = error_of(prism_scene(prism));
    EXPECT_TRUE(has(e, part)) << e;
  }
  // Both shapes, or none.
  const std::string both = R"({
    "grid": { "size": [1, 1, 1], "cell_size": 0.1 }, "time": { "end": 0.1 },
    "materials": { "m": { "density": 1000, "young": 1e6, "poisson": 0.3 } },
    "bodies": [ { "name": "b", "material": "m", "box": { "min": [0.2, 0.2, 0.2], "max": [0.5, 0.5, 0.5] },
                  "prism": {"points": [[0.1, 0.1], [0.5, 0.1], [0.5, 0.5]], "y": [0.2, 0.8]} } ] })";
  const std::string e = error_of(both);
  EXPECT_TRUE(has(e, "bodies[0] needs exactly one shape")) << e;
}

TEST(PrismBody, SeedsExactlyTheCandidatePointsInsideTheWedge) {
  // A right triangle in x-z (legs 0.6 along x and 0.4 along z) extruded over y in [0.2, 0.8].
  const Scene scene = parse_scene(
      prism_scene(R"({"points": [[0.2, 0.1], [0.8, 0.1], [0.2, 0.5]], "y": [0.2, 0.8]})", 0.05, 2), "wedge.json");
  ASSERT_EQ(scene.bodies[0].shape, BodyShapeKind::Prism);
  const ParticleStore P = seed_particles(scene);
  const double spacing = 0.025;
  // Count the lattice points inside by the triangle's own inequality (x - 0.2)/0.6 + (z - 0.1)/0.4 < 1.
  std::size_t expected = 0;
  for (int i = 0; i < 40; ++i)
    for (int k = 0; k < 40; ++k) {
      const double x = (i + 0.5) * spacing, z = (k + 0.5) * spacing;
      if (x >= 0.2 && z >= 0.1 && (x - 0.2) / 0.6 + (z - 0.1) / 0.4 < 1.0) ++expected;
    }
  expected *= 24;  // y: 0.6 / 0.025 layers
  EXPECT_EQ(P.size(), expected);
  double mass = 0.0;
  for (std::size_t p = 0; p < P.size(); ++p) {
    EXPECT_TRUE(body_contains(scene.bodies[0], Vec3(P.x[0][p], P.x[1][p], P.x[2][p])));
    EXPECT_GE(P.x[1][p], 0.2);
    EXPECT_LT(P.x[1][p], 0.8);
    mass += P.mass[p];
  }
  // Mass within the lattice's discretisation of density * area * width = 1000 * 0.12 * 0.6 = 72 kg:
  // the hypotenuse cuts about 0.72 m / 0.025 m = 29 lattice columns, each off by up to half a point.
  EXPECT_NEAR(mass, 72.0, 29 * 24 * 1000 * std::pow(spacing, 3));
  EXPECT_NE(mass, 72.0 * 2);  // not the bounding box
}

TEST(PrismBody, RoundTripsThroughTheResolvedScene) {
  const Scene a = parse_scene(prism_scene(R"({"points": [[0.2, 0.1], [0.8, 0.1], [0.2, 0.5]], "y": [0.2, 0.8]})"), "a");
  const Scene b = parse_scene(scene_to_json(a).dump(), "b");
  ASSERT_EQ(b.bodies[0].shape, BodyShapeKind::Prism);
  EXPECT_EQ(b.bodies[0].prism.points, a.bodies[0].prism.points);
  EXPECT_EQ(b.bodies[0].prism.y1, 0.8);
  EXPECT_EQ(seed_particles(a).size(), seed_particles(b).size());
}

}  // namespace
}  // namespace body_shape_test
}  // namespace talus
