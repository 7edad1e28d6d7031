// The scene reader: defaults, round trip, and one clear message per kind of bad input.
#include "../solver/scene_fixtures.hpp"
#include "talus/core/error.hpp"
#include "talus/scene/element_test_json.hpp"
#include "talus/scene/scene_json.hpp"
#include "talus/solver/solver.hpp"

#include <fmt/core.h>
#include <gtest/gtest.h>

#include <array>
#include <cmath>
#include <string>
#include <vector>

namespace talus {
namespace scene_json_test {
namespace {

const char* kMinimal = R"({
  "grid": { "size": [1, 1, 1], "cell_size": 0.1 },
  "time": { "end": 0.1 },
  "materials": { "m": { "density": 1000, "young": 1e6, "poisson": 0.3 } },
  "bodies": [ { "name": "b", "material": "m", "box": { "min": [0.2, 0.2, 0.2], "max": [0.5, 0.5, 0.5] } } ]
})";

using test::replace_once;
using test::warnings_with;

std::string error_of(const std::string& text) { return test::scene_error_of(text); }

TEST(SceneJson, DefaultsAndRoundTrip) {
  const Scene s = parse_scene(kMinimal, "t");
  EXPECT_EQ(s.grid.cells[0], 10);
  EXPECT_EQ(s.scheme, SchemeKind::Musl);
  EXPECT_DOUBLE_EQ(s.courant, 0.3);
  EXPECT_EQ(s.walls[2][0].type, WallType::Slip);
  const Scene again = parse_scene(scene_to_json(s).dump(), "again");
  EXPECT_EQ(scene_to_json(again), scene_to_json(s));
}

// A scene that would take more steps than any run will (young = 1e29: about 1e10 steps) is warned
// about before it starts; the minimal scene (about 30 steps) is not.
TEST(SceneJson, AnEndlessNumberOfStepsIsWarnedAbout) {
  const auto warned = [](const Scene& s) { return test::warnings_with(s, "the run would take about") > 0; };
  EXPECT_FALSE(warned(parse_scene(kMinimal, "t")));
  EXPECT_TRUE(warned(parse_scene(replace_once(kMinimal, "\"young\": 1e6", "\"young\": 1e29"), "t")));
}

// A material too soft for its wave speed to bound the step (young = 1 Pa: the first step is the whole
// run, and the particles fell through the floor) is warned about; the minimal scene is not, and
// neither is the soft scene without gravity.
TEST(SceneJson, AMaterialTooSoftToBoundTheStepIsWarnedAbout) {
  const auto warned = [](const std::string& text) {
    return test::warnings_with(parse_scene(text, "t"), "is longer than the") > 0;
  };
  const std::string soft =
      replace_once(replace_once(kMinimal, "\"young\": 1e6", "\"young\": 1"), "\"end\": 0.1", "\"end\": 1");
  EXPECT_FALSE(warned(kMinimal));
  EXPECT_TRUE(warned(soft));
  EXPECT_FALSE(warned(replace_once(soft, "\"time\"", "\"gravity\": [0, 0, 0], \"time\"")));
}

// Runout diagnostics measured every step (no history interval) are warned about; with an interval not.
TEST(SceneJson, RunoutEveryStepIsWarnedAbout) {
  const auto warned = [](const std::string& text) {
    return test::warnings_with(parse_scene(text, "t"), "measures the runout every step") > 0;
  };
  const std::string runout = replace_once(kMinimal, "\"time\"", "\"diagnostics\": { \"runout\": {} }, \"time\"");
  EXPECT_FALSE(warned(kMinimal));
  EXPECT_TRUE(warned(runout));
  EXPECT_FALSE(warned(replace_once(runout, "\"time\"", "\"output\": { \"history_interval\": 0.01 }, \"time\"")));
}

// A bed so steep that the sheared cells no longer bound the Courant step, and a profile finer than
// the cells (the runout would be measured along a longer bed than the particles slide on): warned
// about; the shipped terrains are not.
TEST(SceneJson, SteepOrFinelyDetailedTerrainsAreWarnedAbout) {
  const Scene incline = read_scene_file(std::string(TALUS_SOURCE_DIR) + "/inputs/terrain/incline30_coarse.json");
  const auto warned = [&](const std::vector<std::array<double, 2>>& points, double courant, const std::string& what) {
    Scene s = incline;
    s.grid.terrain.points = points;
    s.grid.terrain.radii.clear();
    s.courant = courant;
    return test::warnings_with(s, what);
  };
  const auto plane = [](double degrees) {
    return std::vector<std::array<double, 2>>{{0.0, 8.0 * std::tan(degrees * M_PI / 180.0)}, {8.0, 0.0}};
  };
  const std::string steep = "(its node columns) slopes at";
  EXPECT_EQ(warned(plane(30.0), 0.3, steep), 0);
  EXPECT_EQ(warned(plane(78.0), 0.3, steep), 0);   // courant / cos = 1.44: the block slid as it should
  EXPECT_EQ(warned(plane(80.0), 0.3, steep), 1);   // 1.73: it gained energy and stopped
  EXPECT_EQ(warned(plane(80.0), 0.15, steep), 0);  // 0.86
  // It names the key there is (it said solver.courant), the whole steep stretch (it named one chord),
  // and a courant that does keep the ratio at 1 (it said 0.2 for cos = 0.196: 1.02).
  EXPECT_EQ(warned(plane(80.0), 0.3, "between x = 0 and 8 m"), 1);
  EXPECT_EQ(warned(plane(80.0), 0.3, "time.courant = 0.3 is 1.73 times"), 1);
  EXPECT_EQ(warned(plane(80.0), 0.3, "lower time.courant to 0.17 or less"), 1);  // cos 80 degrees = 0.174
  EXPECT_EQ(warned(plane(79.0), 0.3, "lower time.courant to 0.19 or less"), 1);  // cos 79 degrees = 0.191
  EXPECT_EQ(warned({{0.0, 16.0}, {2.0, 0.0}, {8.0, 0.0}}, 0.3, "between x = 0 and 2 m"), 1);  // 83 degrees, then flat
  // A cliff outside the grid shears no cell: no warning (the grid spans x = 0 .. 8).
  EXPECT_EQ(warned({{-5.0, 20.0}, {-4.9, 8.0 * std::tan(M_PI / 6.0)}, {8.0, 0.0}}, 0.3, steep), 0);
  // A no-data value (-9999) in a profile is a step of nearly 90 degrees.
  EXPECT_EQ(warned({{0.0, 2.0}, {4.0, -9999.0}, {4.1, 1.0}, {8.0, 0.0}}, 0.3, "a no-data value or a step"), 1);
  // Between two node columns (4 and 4.25 m) it shears no cell, but the runout's s runs over it
  // (it was warned about only as "more detail", 232052% longer).
  const auto on_plane = [](double x) { return (8.0 - x) * std::tan(M_PI / 6.0); };
  const std::vector<std::array<double, 2>> spike{{0.0, on_plane(0.0)}, {4.0, on_plane(4.0)}, {4.1, -9999.0}, {4.2, on_plane(4.2)}, {8.0, 0.0}};
  EXPECT_EQ(warned(spike, 0.3, "grid.terrain.points[1] to [2], (4, 2.3094) to (4.1, -9999): the profile rises or falls at "
                               "more than 89 degrees between the grid's node columns (a no-data value or a step"), 1);
  EXPECT_EQ(warned(spike, 0.3, steep), 0);
  EXPECT_EQ(warned(plane(80.0), 0.3, "between the grid's node columns"), 0);
  // Ripples of 2 cm every 0.1 m on a 30-degree plane, cell 0.25 m: 18% more bed than the grid resolves.
  std::vector<std::array<double, 2>> ripples;
  for (int i = 0; i <= 320; ++i) {
    const double x = 0.025 * i;
    ripples.push_back({x, (8.0 - x) * std::tan(M_PI / 6.0) + ((i % 4 == 1) ? 0.02 : (i % 4 == 3) ? -0.02 : 0.0)});
  }
  EXPECT_EQ(warned(ripples, 0.3, "more detail than grid.cell_size"), 1);
  EXPECT_EQ(warned(plane(30.0), 0.3, "more detail than grid.cell_size"), 0);
  // A bed origin off the profile: the bed is not where the profile (and terrain.vtu) says.
  Scene lowered = incline;
  lowered.grid.origin[2] = -0.5;
  EXPECT_EQ(test::warnings_with(lowered, "grid.origin[2] = -0.5 on a terrain grid: the bed"), 1);
  EXPECT_EQ(test::warnings_with(incline, "grid.origin[2]"), 0);
  for (const char* name : {"denlinger_flume.json", "terrain/slope_to_runout_linear.json", "terrain/incline30_fine.json"})
    EXPECT_EQ(test::warnings_with(read_scene_file(std::string(TALUS_SOURCE_DIR) + "/inputs/" + name), "grid.terrain"), 0)
        << name;
}

// A profile whose points do not reach over the grid is continued straight beyond them, silently; and
// the runout plane's default (the end of the last transition) outside the grid was used all the
// same, where a runout_plane_x there is refused. Both are warned about; the shipped scenes are not.
TEST(SceneJson, ATerrainShortOfTheGridAndARunoutPlaneOutsideItAreWarnedAbout) {
  Scene slope = read_scene_file(std::string(TALUS_SOURCE_DIR) + "/inputs/terrain/incline30_coarse.json");  // x = 0 .. 8, h = 0.25
  slope.grid.terrain.points = {{0.0, 2.3094}, {4.0, 0.0}, {8.0, 0.0}};
  slope.grid.terrain.radii = {0.0, 1.0, 0.0};
  slope.runout = RunoutSpec{};
  slope.runout.enabled = true;
  const std::string short_of = "grid.terrain.points cover x = ";
  EXPECT_EQ(test::warnings_with(slope, short_of), 0);
  Scene s = slope;
  s.grid.terrain.points = {{0.0, 2.3094}, {4.0, 0.0}, {6.0, 0.0}};
  EXPECT_EQ(test::warnings_with(s, "grid.terrain.points cover x = [0, 6] m and the grid x = [0, 8] m: the bed continues "
                                   "the end segments straight over 2 m after the last point"), 1);
  s.grid.terrain.points = {{0.5, 2.0207}, {4.0, 0.0}, {7.8, 0.0}};  // within a cell at the end: rounding
  EXPECT_EQ(test::warnings_with(s, "over 0.5 m before the first point, where"), 1);
  s = slope;
  s.grid.origin[0] = 100.0;  // the points in other coordinates than the grid's
  EXPECT_EQ(test::warnings_with(s, "over 100 m after the last point"), 1);
  // The runout plane's default starts at x = 4 + 1 m tan(30 deg / 2) = 4.27 m: outside a grid cut to 3 m.
  const std::string no_plane = "diagnostics.runout.runout_plane_x: its default, the end of the terrain's last transition "
                               "(x = 4.26795 m), lies outside the grid along x, [0, 3]";
  EXPECT_EQ(test::warnings_with(slope, "diagnostics.runout.runout_plane_x"), 0);
  s = slope;
  s.grid.cells[0] = 12;
  EXPECT_EQ(test::warnings_with(s, no_plane), 1);
  s.runout.has_runout_plane = true;  // given (inside the grid): nothing to warn about
  s.runout.runout_plane_x = 2.0;
  EXPECT_EQ(test::warnings_with(s, "diagnostics.runout.runout_plane_x"), 0);
  for (const char* name : {"denlinger_flume.json", "denlinger_flume_abe2005.json", "terrain/slope_to_runout_linear.json"})
    EXPECT_EQ(test::warnings_with(read_scene_file(std::string(TALUS_SOURCE_DIR) + "/inputs/" + name), "runout_plane_x"), 0)
        << name;
}

// An undamped elastic body on a high-friction face is warned about (docs/verification.md, "Near the
// sliding threshold"); with the PIC share measured to cure it, on a low-friction face, or a granular
// body it is not.
TEST(SceneJson, AnUndampedElasticBodyOnAHighFrictionBedIsWarnedAbout) {
  const auto shipped = [](const char* name) { return read_scene_file(std::string(TALUS_SOURCE_DIR) + "/inputs/" + name); };
  const std::string warning = "bodies[0] (\"block\") is linear_elastic on the friction face z- (friction_coefficient 0.55)";
  Scene near = shipped("terrain/incline30_near_threshold.json");
  EXPECT_EQ(test::warnings_with(near, warning), 1);
  near.pic_fraction = 0.01;  // a share smaller than the one measured to cure it
  EXPECT_EQ(test::warnings_with(near, "with solver.pic_fraction = 0.01: near its sliding threshold"), 1);
  near.pic_fraction = 0.05;
  EXPECT_EQ(test::warnings_with(near, "is linear_elastic on the friction face"), 0);
  EXPECT_EQ(test::warnings_with(shipped("terrain/incline30_coarse.json"), "is linear_elastic on the friction face"), 0);  // mu 0.3
  EXPECT_EQ(test::warnings_with(shipped("benchmarks/sand_slide_near_threshold.json"), "on the friction face"), 0);  // sand
}

// On a terrain grid z- is the bed: open, it lets everything that reaches the ground fall through it
// (a slide left the grid whole, without a word). Warned about; an open floor of a flat grid, an open
// side of a terrain grid and the shipped terrain scene are not.
TEST(SceneJson, AnOpenBedOnATerrainGridIsWarnedAbout) {
  const std::string warning = "boundaries.z- = \"open\" on a terrain grid: z- is the bed (grid.terrain), so the "
                              "material leaves through the ground";
  Scene terrain = read_scene_file(std::string(TALUS_SOURCE_DIR) + "/inputs/terrain/incline30_coarse.json");
  EXPECT_EQ(test::warnings_with(terrain, "boundaries.z-"), 0);
  terrain.walls[2][0] = WallSpec{WallType::Open};
  EXPECT_EQ(test::warnings_with(terrain, warning), 1);
  terrain.walls[2][0] = WallSpec{WallType::Slip};
  terrain.walls[1][0] = WallSpec{WallType::Open};
  EXPECT_EQ(test::warnings_with(terrain, "on a terrain grid"), 0);
  Scene flat = parse_scene(kMinimal, "t");
  flat.walls[2][0] = WallSpec{WallType::Open};
  EXPECT_EQ(test::warnings_with(flat, "boundaries.z-"), 0);
}

// A whole number written with a point (a script's json.dumps of a float; JSON Schema counts it an
// integer) is that integer; a fraction is still refused.
TEST(SceneJson, AWholeNumberWithAPointIsAnInteger) {
  const auto with_count = [](const std::string& n) {
    return replace_once(kMinimal, "\"material\": \"m\",", "\"material\": \"m\", \"particles_per_cell\": " + n + ",");
  };
  EXPECT_EQ(parse_scene(with_count("3.0"), "t").bodies[0].particles_per_cell, 3);
  EXPECT_EQ(parse_scene(with_count("3e0"), "t").bodies[0].particles_per_cell, 3);
  EXPECT_NE(error_of(with_count("2.5")).find("bodies[0].particles_per_cell must be an integer"), std::string::npos);
  EXPECT_NE(error_of(with_count("1e9")).find("bodies[0].particles_per_cell = 1000000000.0 is outside the allowed range"),
            std::string::npos)
      << error_of(with_count("1e9"));
}

// A gravity ramp longer than the run: the whole scene ran under part of its gravity without a word.
TEST(SceneJson, AGravityRampLongerThanTheRunIsWarnedAbout) {
  Scene scene = parse_scene(kMinimal, "t");
  scene.gravity_ramp_time = 4.0 * scene.end_time;
  EXPECT_EQ(test::warnings_with(scene, "is longer than time.end"), 1);
  EXPECT_EQ(test::warnings_with(scene, "gravity never reaches its full value (at the end it is 25% of it)"), 1);
  scene.gravity_ramp_time = scene.end_time;
  EXPECT_EQ(test::warnings_with(scene, "gravity_ramp_time"), 0);
}

// Two boxes sharing a volume seed it twice: warned about; boxes that only touch are not.
TEST(SceneJson, OverlappingBoxesAreWarnedAbout) {
  const auto warnings_of = [](const std::string& second_box) {
    const std::string text = replace_once(
        kMinimal, "\"max\": [0.5, 0.5, 0.5] } } ]",
        "\"max\": [0.5, 0.5, 0.5] } }, { \"name\": \"c\", \"material\": \"m\", \"box\": " + second_box + " } ]");
    return test::warnings_with(parse_scene(text, "t"), "bodies[0] (\"b\") and bodies[1] (\"c\") overlap");
  };
  EXPECT_EQ(warnings_of(R"({ "min": [0.4, 0.2, 0.2], "max": [0.8, 0.5, 0.5] })"), 1);
  EXPECT_EQ(warnings_of(R"({ "min": [0.5, 0.2, 0.2], "max": [0.8, 0.5, 0.5] })"), 0);  // touching
}

// The same for a prism over a box, and for a physical box over a terrain-frame one: both seeded the
// shared volume twice without a word (only two boxes in one frame were checked).
TEST(SceneJson, OverlappingBodiesOfAnyShapeOrFrameAreWarnedAbout) {
  const auto with_prism = [](const std::string& points) {
    return parse_scene(replace_once(kMinimal, "\"max\": [0.5, 0.5, 0.5] } } ]",
                                    "\"max\": [0.5, 0.5, 0.5] } }, { \"name\": \"w\", \"material\": \"m\", \"prism\": "
                                    "{ \"points\": " + points + ", \"y\": [0.2, 0.5] } } ]"),
                       "t");
  };
  // the prism covers x in [0.4, 0.8): a third of the box's 6 x 6 x 6 particles
  EXPECT_EQ(test::warnings_with(with_prism("[[0.4, 0.2], [0.8, 0.2], [0.8, 0.5], [0.4, 0.5]]"),
                                "bodies[0] (\"b\") and bodies[1].prism (\"w\") overlap: 72 of the 216 particles of "
                                "bodies[0] (in [0.425, 0.225, 0.225] - [0.475, 0.475, 0.475]) lie inside bodies[1].prism"),
            1);
  EXPECT_EQ(test::warnings_with(with_prism("[[0.5, 0.2], [0.8, 0.2], [0.8, 0.5], [0.5, 0.5]]"), "overlap"), 0);  // touching
  // On a terrain grid: a physical box laid into the terrain-frame block (w in [0, 1] over x in [1, 2])
  Scene terrain = read_scene_file(std::string(TALUS_SOURCE_DIR) + "/inputs/terrain/incline30_coarse.json");
  BodySpec physical = terrain.bodies.front();
  physical.name = "over";
  physical.frame = BoxFrame::Physical;
  physical.box_min = Vec3(1.0, 0.0, 3.9);
  physical.box_max = Vec3(2.0, 0.25, 4.3);
  terrain.bodies.push_back(physical);
  EXPECT_EQ(test::warnings_with(terrain, "bodies[0] (\"block\") and bodies[1] (\"over\") overlap"), 1);
  terrain.bodies.back().box_min[2] = 5.1;  // above the block (its top, 1 m over the bed, is at most 5.04 m)
  terrain.bodies.back().box_max[2] = 5.3;
  EXPECT_EQ(test::warnings_with(terrain, "overlap"), 0);
}

// A box's frame written out as the default, "physical", is the flat grid's own frame: accepted (it was
// refused as if it needed grid.terrain). Only "terrain" needs a bed, and its message says so.
TEST(SceneJson, TheDefaultFrameWrittenOutIsAcceptedOnAFlatGrid) {
  const std::string physical =
      replace_once(kMinimal, "\"max\": [0.5, 0.5, 0.5] }", "\"max\": [0.5, 0.5, 0.5], \"frame\": \"physical\" }");
  EXPECT_EQ(scene_to_json(parse_scene(physical, "t")), scene_to_json(parse_scene(kMinimal, "t")));
  test::expect_variant_error(kMinimal, "\"max\": [0.5, 0.5, 0.5] }",
                             "\"max\": [0.5, 0.5, 0.5], \"frame\": \"terrain\" }",
                             "bodies[0].box.frame = \"terrain\" needs grid.terrain");
  test::expect_variant_error(kMinimal, "\"max\": [0.5, 0.5, 0.5] }", "\"max\": [0.5, 0.5, 0.5], \"frame\": \"bed\" }",
                             "bodies[0].box.frame = \"bed\" is not one of: physical, terrain");
}

// Units written wrong pass every range: warned about where the value is far from granular matter's.
TEST(SceneJson, ValuesThatLookLikeTheWrongUnitAreWarnedAbout) {
  const auto warned = [](const std::string& from, const std::string& to, const std::string& what) {
    return test::warnings_with(parse_scene(replace_once(kMinimal, from, to), "t"), what);
  };
  const std::string friction_face = R"("bodies": [)";
  const auto face = [&](double mu) {
    return fmt::format(R"("boundaries": {{ "z-": {{ "type": "friction", "friction_coefficient": {} }} }}, "bodies": [)", mu);
  };
  EXPECT_EQ(warned(friction_face, face(29), "boundaries.z-.friction_coefficient = 29 is tan 88.0 degrees: a coefficient, "
                                            "not an angle in degrees?"), 1);
  EXPECT_EQ(warned(friction_face, face(0.58), "not an angle in degrees"), 0);
  const auto dp = [](double phi) {
    return fmt::format(R"("poisson": 0.3, "model": "drucker_prager", "friction_angle": {})", phi);
  };
  EXPECT_EQ(warned("\"poisson\": 0.3", dp(0.61), "materials.m.friction_angle = 0.61 degrees: an angle in degrees, not "
                                                 "radians? (0.61 rad is 35 degrees)"), 1);
  EXPECT_EQ(warned("\"poisson\": 0.3", dp(35), "friction_angle"), 0);
  const auto mu_i = [](double mu_s, double mu_2) {
    return fmt::format(R"("poisson": 0.3, "model": "mu_i", "mu_s": {}, "mu_2": {}, "grain_density": 2450)", mu_s, mu_2);
  };
  EXPECT_EQ(warned("\"poisson\": 0.3", mu_i(35, 40), "materials.m.mu_2 = 40 (mu_s = 35) is tan 88.6 degrees"), 1);
  EXPECT_EQ(warned("\"poisson\": 0.3", mu_i(0.38, 0.64), "mu_2"), 0);
  // mu_s = 35 with the default mu_2 was refused as mu_2's fault alone
  EXPECT_NE(error_of(replace_once(kMinimal, "\"poisson\": 0.3", R"("poisson": 0.3, "model": "mu_i", "mu_s": 35)"))
                .find("mu_s and mu_2 are friction coefficients (tan of the angle), not angles in degrees"),
            std::string::npos);
}

// A μ(I) packing denser than its grains (solid fraction above 1) is no packing: refused.
TEST(SceneJson, MuIPackingDenserThanItsGrainsIsRefused) {
  const std::string mu_i = replace_once(kMinimal, "\"poisson\": 0.3", "\"poisson\": 0.3, \"model\": \"mu_i\", \"grain_density\": 2450");
  EXPECT_NO_THROW(parse_scene(mu_i, "t"));
  test::expect_variant_error(mu_i, "\"grain_density\": 2450", "\"grain_density\": 100",
                             "materials.m.density = 1000 is above grain_density = 100: a packing cannot be denser");
}

TEST(SceneJson, BadInputNamesTheKeyAndTheRange) {
  const std::string ok = kMinimal;
  test::expect_variant_error(ok, "\"poisson\": 0.3", "\"poisson\": 0.5", "materials.m.poisson = 0.5 is outside the allowed range (-1, 0.5)");
  test::expect_variant_error(ok, "\"end\": 0.1", "\"end\": -1", "time.end");
  test::expect_variant_error(ok, "\"end\": 0.1", "\"end\": 0.1, \"courant\": 1.0", "time.courant = 1 is outside the allowed range (0, 1)");
  test::expect_variant_error(ok, "\"time\"", "\"tmie\": {}, \"time\"", "unknown key tmie");
  test::expect_variant_error(ok, "\"time\"", "\"solver\": { \"block_cells\": 2 }, \"time\"",
                             "solver.block_cells = 2: must be 0 (automatic) or 3..64 for the linear shape");
  test::expect_variant_error(ok, "\"time\"", "\"solver\": { \"shape\": \"bspline2\", \"block_cells\": 4 }, \"time\"",
                             "solver.block_cells = 4: must be 0 (automatic) or 5..64 for the bspline2 shape");
  test::expect_variant_error(ok, "\"density\": 1000", "\"density\": \"heavy\"", "materials.m.density must be a number");
  test::expect_variant_error(ok, "\"material\": \"m\"", "\"material\": \"sand\"", "bodies[0].material = \"sand\" names no material");
  test::expect_variant_error(ok, "\"max\": [0.5, 0.5, 0.5]", "\"max\": [0.5, 0.5, 1.5]", "lies outside the grid");
  // round-off past the grid's faces is accepted on both sides alike (at an origin of 0 the lower face
  // allowed none: a min of -1e-17 was refused while a max 1 ulp past the upper face was accepted)
  EXPECT_NO_THROW(parse_scene(replace_once(ok, "\"min\": [0.2, 0.2, 0.2]", "\"min\": [-1e-17, 0.2, 0.2]"), "t.json"));
  EXPECT_NO_THROW(parse_scene(replace_once(ok, "\"max\": [0.5, 0.5, 0.5]", "\"max\": [0.5, 0.5, 1.0000000000000002]"), "t.json"));
  test::expect_variant_error(ok, "\"min\": [0.2, 0.2, 0.2]", "\"min\": [-1e-6, 0.2, 0.2]",
                             "bodies[0].box.min[0] = -1e-06 (x) lies outside the grid [0, 1]: the box [-1e-06, 0.5] along axis 0 "
                             "lies partly outside it");
  test::expect_variant_error(ok, "\"cell_size\": 0.1", "\"cell_size\": 0.3", "grid.size[0] = 1 must be a positive whole multiple of grid.cell_size");
  // a cell size too small for the cell limit names the limit, however small (at 1e-20 the count has no
  // integer and it was called no whole divisor of the size)
  test::expect_variant_error(ok, "\"cell_size\": 0.1", "\"cell_size\": 1e-6",
                             "grid.size[0] / grid.cell_size = 1e+06 cells; at most 100000 per axis");
  test::expect_variant_error(ok, "\"cell_size\": 0.1", "\"cell_size\": 1e-20",
                             "grid.size[0] / grid.cell_size = 1e+20 cells; at most 100000 per axis");
  test::expect_variant_error(ok, "\"young\": 1e6", "\"young\": 0", "materials.m.young");
  test::expect_variant_error(ok, "\"time\"", "\"boundaries\": { \"x-\": 1 }, \"time\"",
                             "boundaries.x- must be a string (open, slip, fixed, periodic) or an object with type "
                             "(friction needs one), got number");
  EXPECT_NE(error_of("{ \"grid\": ").find("malformed JSON"), std::string::npos);
  test::expect_variant_error(ok, "\"time\"", "\"solver\": { \"scheme\": \"rk4\" }, \"time\"", "solver.scheme = \"rk4\" is not one of: musl, usl");
}

// Positions are absolute: a grid far from 0 cannot resolve its cells (at 1e15 m a block of 0.02 m
// cells was seeded as one plane) and is refused; map coordinates (UTM, 5e6 m) are still fine.
TEST(SceneJson, AGridTooFarFromTheOriginToResolveItsCellsIsRefused) {
  test::expect_variant_error(kMinimal, "\"grid\": { \"size\"", "\"grid\": { \"origin\": [1e12, 0, 0], \"size\"",
                             "grid.origin: coordinates reach 1e+12 m, where doubles are 0.000122 m apart, more than "
                             "1e-6 of grid.cell_size = 0.1");
  std::string utm = replace_once(kMinimal, "\"grid\": { \"size\"", "\"grid\": { \"origin\": [5e5, 5e6, 0], \"size\"");
  utm = replace_once(utm, "\"min\": [0.2, 0.2, 0.2], \"max\": [0.5, 0.5, 0.5]",
                     "\"min\": [500000.2, 5000000.2, 0.2], \"max\": [500000.5, 5000000.5, 0.5]");
  EXPECT_NO_THROW((void)parse_scene(utm, "utm.json"));
}

// The element test reads its material with the scene's Drucker-Prager fields (issue 22): the
// same keys, the same ranges, the same messages, and "apex" for the default tension cut-off in both.
TEST(SceneJson, DruckerPragerKeysFollowOneRuleInScenesAndElementTests) {
  const std::string sand = replace_once(kMinimal, "\"density\": 1000, \"young\": 1e6, \"poisson\": 0.3",
                                        "\"model\": \"drucker_prager\", \"density\": 1000, \"young\": 1e6, "
                                        "\"poisson\": 0.3, \"friction_angle\": 30, \"tension_cutoff\": \"apex\"");
  const Scene s = parse_scene(sand, "t");
  EXPECT_TRUE(std::isinf(s.materials[0].drucker_prager.tension_cutoff));
  EXPECT_EQ(scene_to_json(parse_scene(scene_to_json(s).dump(), "again")), scene_to_json(s));
  const std::string spec_material =
      R"({"young": 1e6, "poisson": 0.3, "friction_angle": 30, "tension_cutoff": "apex"})";
  const std::string spec_path = R"({"type": "oedometer", "strain": 0.01, "increments": 10})";
  auto spec_error = [&](const std::string& from, const std::string& to) {
    try {
      parse_element_test(R"({"material": )" + replace_once(spec_material, from, to) + R"(, "path": )" + spec_path + "}",
                         "spec.json");
    } catch (const Error& e) {
      return std::string(e.what());
    }
    return std::string("no error");
  };
  EXPECT_TRUE(std::isinf(parse_element_test(R"({"material": )" + spec_material + R"(, "path": )" + spec_path + "}",
                                            "spec.json")
                             .material.tension_cutoff));
  // "@" stands for the material's key path: materials.m. in the scene, material. in the spec.
  const std::vector<std::array<std::string, 3>> cases = {
      {"\"poisson\": 0.3", "\"poisson\": 0.5", "@poisson = 0.5 is outside the allowed range [0, 0.5)"},
      {"\"friction_angle\": 30", "\"friction_angle\": 95", "@friction_angle = 95 is out of range; allowed (0, 90)"},
      {"\"apex\"", "\"top\"", "@tension_cutoff = \"top\" is not \"apex\" or a mean stress >= 0"},
      {"\"apex\"", "-1", "@tension_cutoff = -1 is out of range"},
      {"\"friction_angle\": 30", "\"friction_angle\": 30, \"frction\": 1", "unknown key @frction"},
  };
  auto with_prefix = [](std::string message, const std::string& prefix) {
    return message.replace(message.find('@'), 1, prefix);
  };
  for (const auto& [from, to, message] : cases) {
    const std::string in_scene = error_of(replace_once(sand, from, to));
    const std::string in_spec = spec_error(from, to);
    EXPECT_NE(in_scene.find(with_prefix(message, "materials.m.")), std::string::npos) << in_scene;
    EXPECT_NE(in_spec.find(with_prefix(message, "material.")), std::string::npos) << in_spec;
  }
}

TEST(SceneJson, EmptyBodyIsRefusedWhenSeeding) {
  // A box thinner than the particle spacing passes the reader but holds no particle.
  const std::string thin = replace_once(kMinimal, "\"max\": [0.5, 0.5, 0.5]", "\"max\": [0.5, 0.5, 0.21]");
  const Scene scene = parse_scene(thin, "t");
  try {
    Solver solver(scene);
    FAIL() << "an empty body must be refused";
  } catch (const Error& e) {
    EXPECT_EQ(e.exit_code(), 2);
    EXPECT_NE(std::string(e.what()).find("bodies[0] (\"b\") holds no particle"), std::string::npos) << e.what();
  }
}

// A first-day user's scenes: a material no body uses, checkpoints due more often than a step, a
// material named "", and the messages that told them too little.
TEST(SceneJson, AnUnusedMaterialAndCheckpointsAtEveryStepAreWarnedAbout) {
  const std::string ok = kMinimal;
  EXPECT_EQ(warnings_with(parse_scene(ok, "t"), "is used by no body"), 0);
  const std::string two = replace_once(ok, "\"materials\": { ", "\"materials\": { \"spare\": { \"density\": 1000, \"young\": 1e6, \"poisson\": 0.3 }, ");
  EXPECT_EQ(warnings_with(parse_scene(two, "t"), "materials.spare is used by no body"), 1);
  const Scene scene = parse_scene(ok, "t");
  const double dt = scene.initial_time_step();
  const auto with_interval = [&](double interval) {
    return parse_scene(replace_once(ok, "\"time\"", fmt::format("\"output\": {{ \"checkpoint_interval\": {} }}, \"time\"", interval)), "t");
  };
  EXPECT_EQ(warnings_with(with_interval(0.5 * dt), "is shorter than the time step"), 1);
  EXPECT_EQ(warnings_with(with_interval(10.0 * dt), "is shorter than the time step"), 0);
  EXPECT_EQ(warnings_with(with_interval(0.0), "is shorter than the time step"), 0);
}

TEST(SceneJson, FirstDayMessagesSayTheTrueRangeAndWhereAKeyBelongs) {
  const std::string ok = kMinimal;
  test::expect_variant_error(ok, "\"materials\": { \"m\"", "\"materials\": { \"\"",
                             "materials has a material named \"\": give it a name");
  // 0 was refused too, after "outside the allowed range [0, inf)"
  test::expect_variant_error(ok, "\"size\": [1, 1, 1]", "\"size\": [-1.2, 1, 1]",
                             "grid.size[0] = -1.2 is outside the allowed range (0, inf)");
  test::expect_variant_error(ok, "\"size\": [1, 1, 1]", "\"size\": [0, 1, 1]",
                             "grid.size[0] = 0 is outside the allowed range (0, inf)");
  test::expect_variant_error(ok, "\"size\": [1, 1, 1]", "\"size\": [1, 1, 1], \"origin\": [\"a\", 0, 0]",
                             "grid.origin[0] must be a finite number, got \"a\"");
  test::expect_variant_error(ok, "\"time\"", "\"boundaries\": { \"x-\": { \"type\": \"slip\", \"friction_coefficient\": 0.3 } }, \"time\"",
                             "boundaries.x-.friction_coefficient belongs to \"type\": \"friction\" faces; this face is \"slip\"");
  test::expect_variant_error(ok, "\"time\": { \"end\": 0.1 },", "\"time\": { \"end\": 0.1 },\n  // the materials\n",
                             "JSON has no comments: put notes in a \"comment\" key");
  test::expect_variant_error(ok, "\"time\": { \"end\": 0.1 },", "\"time\": { \"end\": 0.1 }, /* the materials */",
                             "JSON has no comments");
  EXPECT_EQ(error_of(replace_once(ok, "\"time\"", "\"time\" \"x\"")).find("comments"), std::string::npos);
}

}  // namespace
}  // namespace scene_json_test
}  // namespace talus
