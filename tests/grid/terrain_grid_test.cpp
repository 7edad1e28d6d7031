// The terrain-following grid (Abe, Johansson & Konagai 2005, eq. 19-20 in 3D, docs/theory.md "Terrain-following grid"):
// the bed sampled at the node columns, its node normals (kinks: the normalised average), the
// shape functions through the (x, y, w) map, and seeding bodies onto the terrain.
#include "talus/core/error.hpp"
#include "talus/grid/grid.hpp"
#include "talus/particles/seeding.hpp"
#include "talus/scene/scene_json.hpp"
#include "talus/shape/bspline.hpp"
#include "talus/shape/gimp.hpp"
#include "talus/shape/linear.hpp"
#include "talus/transfer/stencil.hpp"

#include <fmt/core.h>

#include <gtest/gtest.h>

#include <cmath>
#include <random>

namespace talus {
namespace terrain_grid_test {
namespace {

constexpr double kPi = 3.14159265358979323846;
const double kTan30 = std::tan(30.0 * kPi / 180.0);

/// A 30-degree slope from x = 0 down to a kink at x = 2 (a node column for h = 0.25), then flat.
GridGeometry slope_geometry(double radius = 0.0) {
  GridGeometry g;
  g.origin = Vec3(0.0, 0.0, 0.0);
  g.h = 0.25;
  g.cells = {16, 2, 8};
  g.terrain.points = {{0.0, 2.0 * kTan30}, {2.0, 0.0}, {4.0, 0.0}};
  g.terrain.radii = {0.0, radius, 0.0};
  return g;
}

TEST(TerrainGrid, BedNodesLieOnTheProfileAndCarryItsNormal) {
  const GridGeometry g = slope_geometry(0.6);
  const Grid grid(g);
  const TerrainProfile profile(g.terrain);
  const ProfileTerrain& bed = grid.profile_terrain();
  ASSERT_EQ(bed.columns(), g.nodes()[0]);
  for (int i = 0; i < bed.columns(); ++i) {
    const double x = g.node_position(0, i);
    EXPECT_EQ(bed.node_height(i), profile.height(x)) << i;
    // between nodes the floor is the chord (Abe, Johansson & Konagai 2005, eq. 20): linear in x within a cell
    const double mid = x + 0.5 * g.h;
    if (i + 1 < bed.columns()) {
      EXPECT_NEAR(bed.height(mid), 0.5 * (bed.node_height(i) + bed.node_height(i + 1)), 1e-14);
    }
  }
  // on the straight parts the node normal is the profile's normal
  for (double x : {0.5, 1.0, 3.5}) {
    const int i = static_cast<int>(std::lround(g.to_grid(0, x)));
    EXPECT_NEAR((bed.node_normal(i) - profile.normal(x)).norm(), 0.0, 1e-12) << x;
  }
  // chord sag on the arc: the grid's floor lies above the concave-up profile by at most h^2 / (8 r)
  double sag = 0.0;
  for (double x = 1.0; x < 3.0; x += 0.01) {
    const double d = bed.height(x) - profile.height(x);
    EXPECT_GE(d, -1e-14);
    sag = std::max(sag, d);
  }
  EXPECT_LE(sag, g.h * g.h / (8.0 * 0.6) + 1e-12);
}

TEST(TerrainGrid, KinkNodeNormalIsTheNormalisedAverageOfBothSides) {
  const GridGeometry g = slope_geometry(0.0);
  const Grid grid(g);
  const ProfileTerrain& bed = grid.profile_terrain();
  const int kink = static_cast<int>(std::lround(g.to_grid(0, 2.0)));
  const Vec3 left = Vec3(kTan30, 0.0, 1.0).normalized(), right(0.0, 0.0, 1.0);
  EXPECT_NEAR((bed.node_normal(kink) - (left + right).normalized()).norm(), 0.0, 1e-12);
  EXPECT_NEAR(bed.node_normal(kink).norm(), 1.0, 1e-15);
  // 15 degrees: halfway between the two faces
  EXPECT_NEAR(std::atan2(bed.node_normal(kink)[0], bed.node_normal(kink)[2]) * 180.0 / kPi, 15.0, 1e-9);
  // the slope a particle sees jumps at the kink column: the right cell's floor from the node on
  EXPECT_NEAR(bed.slope(1.99), -kTan30, 1e-12);
  EXPECT_EQ(bed.slope(2.0), 0.0);
}

/// Partition of unity and sum grad N = 0 everywhere (also across kinks: the map keeps them); linear
/// fields in physical (x, y, z) reproduced exactly where the map is affine over the support, i.e.
/// for linear shapes everywhere (isoparametric cells) and for the wider supports away from the
/// columns where the floor bends. Returns the largest error of the reproduced gradient of z.
template <class Shape>
double check_terrain_stencil(double x_lo, double x_hi, bool expect_linear_exact) {
  const GridGeometry g = slope_geometry(0.0);
  const Grid grid(g);
  const ProfileTerrain& bed = grid.profile_terrain();
  std::mt19937 rng(5);
  std::uniform_real_distribution<double> ux(x_lo, x_hi), uy(0.1, 0.4), uw(0.6, 1.4);
  constexpr int N = Shape::kNodes;
  const double hw[3] = {0.25, 0.25, 0.25};  // GIMP: a quarter cell (2 particles per cell)
  double worst = 0.0;
  Stencil<Shape> s;
  for (int trial = 0; trial < 300; ++trial) {
    const double x = ux(rng), y = uy(rng), w = uw(rng);
    const double z = w + bed.height(x);
    s.evaluate(grid, bed, x, y, z, hw);
    int base[3];
    double w1[N], dw1[N];
    Shape::weights(g.to_grid(0, x), hw[0], base[0], w1, dw1);
    Shape::weights(g.to_grid(1, y), hw[1], base[1], w1, dw1);
    Shape::weights(g.to_grid(2, w), hw[2], base[2], w1, dw1);
    double sum = 0.0;
    Vec3 grad_sum = Vec3::Zero(), position = Vec3::Zero();
    Mat3 grad_x = Mat3::Zero();
    for (int a = 0; a < N; ++a)
      for (int b = 0; b < N; ++b)
        for (int c = 0; c < N; ++c) {
          const double wt = s.wx[a] * s.wy[b] * s.wz[c];
          Vec3 grad;
          s.gradient(a, b, c, grad[0], grad[1], grad[2]);
          const int i = base[0] + a;
          const Vec3 xi(g.node_position(0, i), g.node_position(1, base[1] + b),
                        g.node_position(2, base[2] + c) + bed.node_height(i));
          sum += wt;
          grad_sum += grad;
          position += wt * xi;
          grad_x += xi * grad.transpose();
        }
    EXPECT_NEAR(sum, 1.0, 1e-14);
    EXPECT_NEAR(grad_sum.norm(), 0.0, 1e-11);
    const double err = (grad_x - Mat3::Identity()).norm();
    worst = std::max(worst, err);
    if (expect_linear_exact) {
      EXPECT_NEAR((position - Vec3(x, y, z)).norm(), 0.0, 1e-13);
      EXPECT_NEAR(err, 0.0, 1e-11);
    }
  }
  return worst;
}

TEST(TerrainGrid, LinearShapesAreIsoparametricEverywhere) {
  check_terrain_stencil<LinearShape>(0.05, 3.95, true);
}

TEST(TerrainGrid, WiderSupportsAreExactOnStraightSegmentsAndBoundedAtAKink) {
  // wholly on the slope or wholly on the runout (support: 1 cell below, 2 above the particle's cell)
  check_terrain_stencil<UGimpShape>(0.5, 1.45, true);
  check_terrain_stencil<QuadraticBSplineShape>(2.55, 3.5, true);
  check_terrain_stencil<UGimpShape>(2.55, 3.5, true);
  // supports straddling the kink: partition of unity and sum grad N = 0 still hold (checked
  // inside); the gradient of a linear field is off by at most the slope jump (tan 30 = 0.577)
  // times the share of the support beyond the kink (docs/theory.md)
  const double gimp = check_terrain_stencil<UGimpShape>(1.5, 2.5, false);
  const double bspline = check_terrain_stencil<QuadraticBSplineShape>(1.5, 2.5, false);
  EXPECT_GT(gimp, 0.01);  // the defect is real ...
  EXPECT_LT(gimp, kTan30);  // ... and bounded by the slope jump
  EXPECT_GT(bspline, 0.01);
  EXPECT_LT(bspline, kTan30);
  std::printf("linear-field gradient error across a 30-degree kink: ugimp %.3f, bspline2 %.3f\n", gimp, bspline);
}

const char* kSlopeScene = R"({
  "grid": { "origin": [0, 0, 0], "size": [4, 0.5, 2], "cell_size": 0.25,
            "terrain": { "points": [[0, 1.1547005383792515], [2, 0], [4, 0]], "radii": [0, 0.6, 0] } },
  "time": { "end": 0.1 },
  "materials": { "m": { "density": 1000.0, "young": 1.0e6, "poisson": 0.3 } },
  "bodies": [ BODY ]
})";

Scene slope_scene(const std::string& body) {
  std::string text = kSlopeScene;
  text.replace(text.find("BODY"), 4, body);
  return parse_scene(text, "slope");
}

TEST(TerrainGrid, SeedingFillsTheBoxAboveTheBedWithEqualVolumes) {
  // a physical box reaching below the bed: the bed clips it
  const Scene scene = slope_scene(R"({ "name": "pile", "material": "m", "particles_per_cell": 2,
      "box": { "min": [0.5, 0, 0], "max": [1.5, 0.5, 1.2] } })");
  const ParticleStore P = seed_particles(scene);
  const Grid grid(scene.grid);
  ASSERT_GT(P.size(), 100u);
  const double v = std::pow(0.125, 3);
  double volume = 0.0;
  for (std::size_t p = 0; p < P.size(); ++p) {
    EXPECT_GT(grid.w_of(P.x[0][p], P.x[2][p]), 0.0);
    EXPECT_LT(P.x[2][p], 1.2);
    EXPECT_GE(P.x[0][p], 0.5);
    EXPECT_EQ(P.volume[p], v);
    volume += P.volume[p];
  }
  // the box above the straight 30-degree bed: a trapezoid of area int_{0.5}^{1.5} (1.2 - z_b) dx
  const double area = 1.0 * (1.2 - (2.0 - 1.0) * kTan30);
  EXPECT_NEAR(volume / (area * 0.5), 1.0, 0.04);
  // the clip is not silent: the scene warns once, with the share of the box's points the bed took
  // (the seed lattice is w = (k + 1/2) 0.125 above the straight bed z_b = (2 - x) tan 30 in every
  // column x; the box holds the lattice points with 0 <= w + z_b < 1.2, k < 0 among them below the bed)
  const std::vector<std::string> warnings = scene_warnings(scene);
  ASSERT_EQ(warnings.size(), 1u);
  EXPECT_NE(warnings[0].find("bodies[0] (\"pile\") reaches below the bed"), std::string::npos) << warnings[0];
  int in_box = 0, above_bed = 0;
  for (int i = 0; i < 8; ++i) {
    const double zb = (2.0 - (0.5 + (i + 0.5) * 0.125)) * kTan30;
    for (int k = -20; k < 20; ++k) {
      const double z = (k + 0.5) * 0.125 + zb;
      if (z < 0.0 || z >= 1.2) continue;
      ++in_box;
      above_bed += k >= 0;
    }
  }
  ASSERT_EQ(static_cast<std::size_t>(above_bed) * 4, P.size());  // 4 planes along y
  const double share = 100.0 * (in_box - above_bed) / in_box;
  EXPECT_NE(warnings[0].find(fmt::format("{:.3g}% of its particles are not seeded", share)), std::string::npos)
      << warnings[0] << " (expected " << share << "%)";
  // a terrain-frame box: cells of the grid, whole
  const Scene layer = slope_scene(R"({ "name": "layer", "material": "m", "particles_per_cell": 2,
      "box": { "min": [0.5, 0, 0], "max": [1.5, 0.5, 0.5], "frame": "terrain" } })");
  EXPECT_EQ(seed_particles(layer).size(), 4u * 2 * 2 * 8);  // 4 x 2 x 2 cells, 2^3 particles each
}

// The bound that refuses scenes of more than 2^31 particles must stay a bound on a terrain grid:
// clipped to the grid's extent in z (physical boxes) or in w (boxes in the terrain's frame).
TEST(TerrainGrid, TheParticleCountBoundHoldsForBothBoxFrames) {
  auto scene_with = [](const char* body, bool raised_bed) {
    std::string text = kSlopeScene;
    text.replace(text.find("BODY"), 4, body);
    if (raised_bed) {  // the bed 10 m higher: a box in the terrain's frame lies in w, far below the bed's z
      const std::string bed = "[[0, 1.1547005383792515], [2, 0], [4, 0]]";
      text.replace(text.find(bed), bed.size(), "[[0, 11.1547005383792515], [2, 10], [4, 10]]");
    }
    return parse_scene(text, "bound");
  };
  const char* pile = R"({ "name": "pile", "material": "m", "particles_per_cell": 2,
                          "box": { "min": [0.5, 0, 0], "max": [1.5, 0.5, 1.2] } })";
  const char* layer = R"({ "name": "layer", "material": "m", "particles_per_cell": 2,
                           "box": { "min": [0.5, 0, 0], "max": [3.5, 0.5, 0.5], "frame": "terrain" } })";
  for (const Scene& scene : {scene_with(pile, false), scene_with(layer, false), scene_with(layer, true)}) {
    const std::size_t seeded = seed_particles(scene).size();
    ASSERT_GT(seeded, 0u);
    EXPECT_GE(particle_count_bound(scene), double(seeded)) << scene.bodies[0].name;
  }
}

TEST(TerrainGrid, BadTerrainInputNamesTheKey) {
  auto message = [](const std::string& body, const std::string& terrain) {
    std::string text = kSlopeScene;
    text.replace(text.find("BODY"), 4, body);
    const std::size_t at = text.find("\"terrain\"");
    const std::size_t end = text.find("} }", at) + 1;
    text.replace(at, end - at, terrain);
    try {
      Scene s = parse_scene(text, "bad");
      (void)seed_particles(s);
    } catch (const Error& e) {
      return std::string(e.what());
    }
    return std::string("no error");
  };
  const std::string box = R"({ "name": "pile", "material": "m", "box": { "min": [0.5, 0, 0], "max": [1.5, 0.5, 1.2] } })";
  EXPECT_NE(message(box, R"("terrain": { "points": [[0, 1]] })").find("grid.terrain.points"), std::string::npos);
  EXPECT_NE(message(box, R"("terrain": { "points": [[0, 1], [0, 2]] })").find("grid.terrain.points[1]"), std::string::npos);
  EXPECT_NE(message(box, R"("terrain": { "points": [[0, 1], [1, 0], [2, 0]], "radii": [0, -1, 0] })").find("grid.terrain.radii[1]"),
            std::string::npos);
  EXPECT_NE(message(box, R"("terrain": { "points": [[0, 1], [1, 0], [2, 0]], "radii": [0, 50, 0] })").find("grid.terrain.radii"),
            std::string::npos);
  EXPECT_NE(message(box, R"("terrain": { "points": [[0, 1], [1, 0]], "slope": 2 })").find("grid.terrain.slope"), std::string::npos);
  // a body wholly below the bed is named
  const std::string below = R"({ "name": "buried", "material": "m", "box": { "min": [0.5, 0, -1.0], "max": [1.5, 0.5, 0.0] } })";
  const std::string m = message(below, R"("terrain": { "points": [[0, 1.1547005383792515], [2, 0], [4, 0]] })");
  EXPECT_NE(m.find("buried"), std::string::npos) << m;
  EXPECT_NE(m.find("below the bed"), std::string::npos) << m;
  // a body wholly above the grid's top is not said to lie below the bed
  const std::string high = R"({ "name": "high", "material": "m", "box": { "min": [0.5, 0, 5.0], "max": [1.5, 0.5, 6.0] } })";
  const std::string h = message(high, R"("terrain": { "points": [[0, 1.1547005383792515], [2, 0], [4, 0]] })");
  EXPECT_NE(h.find("\"high\") reaches above the grid's top"), std::string::npos) << h;
  EXPECT_NE(h.find("all of its x range"), std::string::npos) << h;
  // a body far above the grid whose box alone would hold about 1e11 particles: named as above the
  // grid, not refused as too many particles (the bound counts only what lies within the grid's extent)
  const std::string huge = R"({ "name": "huge", "material": "m", "box": { "min": [0.5, 0, 1.0e6], "max": [1.5, 0.5, 1.0e9] } })";
  const std::string far = message(huge, R"("terrain": { "points": [[0, 1.1547005383792515], [2, 0], [4, 0]] })");
  EXPECT_NE(far.find("\"huge\") reaches above the grid's top"), std::string::npos) << far;
  // a body reaching above the grid's top (w = 2 above the bed)
  const std::string tall = R"({ "name": "tall", "material": "m", "box": { "min": [2.5, 0, 0], "max": [3.5, 0.5, 2.5] } })";
  EXPECT_NE(message(tall, R"("terrain": { "points": [[0, 1.1547005383792515], [2, 0], [4, 0]] })").find("tall"),
            std::string::npos);
  // a bed 1e5 m above the body, or 1e5 m below it: refused at once (the explanation walked every seed
  // point between the body and the grid, minutes for these)
  const std::string far_below = message(box, R"("terrain": { "points": [[0, 100000], [2, 100000], [4, 100000]] })");
  EXPECT_NE(far_below.find("below the bed"), std::string::npos) << far_below;
  const std::string far_above = message(box, R"("terrain": { "points": [[0, -100000], [2, -100000], [4, -100000]] })");
  EXPECT_NE(far_above.find("reaches above the grid's top (w = "), std::string::npos) << far_above;
}

// The run echoes the resolved scene (scene.json); read back, it must describe the same terrain.
TEST(TerrainGrid, ResolvedSceneRoundTripsTheTerrainAndTheBoxFrame) {
  const Scene scene = slope_scene(R"({ "name": "layer", "material": "m",
      "box": { "min": [0.5, 0, 0], "max": [1.5, 0.5, 0.5], "frame": "terrain" } })");
  const Scene again = parse_scene(scene_to_json(scene).dump(), "echo");
  EXPECT_EQ(again.grid.terrain.points, scene.grid.terrain.points);
  EXPECT_EQ(again.grid.terrain.radii, scene.grid.terrain.radii);
  EXPECT_EQ(again.bodies[0].frame, BoxFrame::Terrain);
  EXPECT_EQ(seed_particles(again).x[2], seed_particles(scene).x[2]);
}

TEST(TerrainGrid, FrameKeyNeedsATerrain) {
  try {
    (void)parse_scene(R"({ "grid": { "size": [1, 1, 1], "cell_size": 0.25 }, "time": { "end": 0.1 },
      "materials": { "m": { "density": 1000.0, "young": 1.0e6, "poisson": 0.3 } },
      "bodies": [ { "name": "b", "material": "m", "box": { "min": [0, 0, 0], "max": [1, 1, 1], "frame": "terrain" } } ] })",
                      "flat");
    FAIL();
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find("bodies[0].box.frame"), std::string::npos) << e.what();
  }
}

}  // namespace
}  // namespace terrain_grid_test
}  // namespace talus
