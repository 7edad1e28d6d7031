// Mistakes of a user writing a landslide scene of their own that no range refuses: a bed rising
// along +x under the runout diagnostics, values in another unit than the key's, a gate inside the
// mass, a kink between node columns; and the messages of two errors they met.
#include "../solver/scene_fixtures.hpp"
#include "talus/scene/scene_json.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <string>

namespace talus {
namespace authoring_warnings_test {
namespace {

using test::replace_once;
using test::warnings_with;

// The user's scene: a profile surveyed from the toe up (rising along +x), a 5 m slab near its top.
const char* kRising = R"({
  "grid": { "size": [120, 2, 16], "cell_size": 2,
            "terrain": { "points": [[0, 0], [30, 3], [50, 12], [70, 28], [95, 48], [120, 60]] } },
  "time": { "end": 1 },
  "materials": { "sand": { "density": 1800, "young": 5e6, "poisson": 0.3 } },
  "bodies": [ { "name": "slab", "material": "sand",
                "box": { "min": [92, 0, 0], "max": [112, 2, 5], "frame": "terrain" } } ],
  "boundaries": { "z-": { "type": "friction", "friction_coefficient": 0.5 } },
  "output": { "history_interval": 0.01 },
  "diagnostics": { "runout": {} }
})";

// The same scene mirrored (x -> 120 - x): the bed descends along +x.
const char* kDescending = R"({
  "grid": { "size": [120, 2, 16], "cell_size": 2,
            "terrain": { "points": [[0, 60], [25, 48], [50, 28], [70, 12], [90, 3], [120, 0]] } },
  "time": { "end": 1 },
  "materials": { "sand": { "density": 1800, "young": 5e6, "poisson": 0.3 } },
  "bodies": [ { "name": "slab", "material": "sand",
                "box": { "min": [8, 0, 0], "max": [28, 2, 5], "frame": "terrain" } } ],
  "boundaries": { "z-": { "type": "friction", "friction_coefficient": 0.5 } },
  "output": { "history_interval": 0.01 },
  "diagnostics": { "runout": {} }
})";

Scene shipped(const std::string& name) { return read_scene_file(std::string(TALUS_SOURCE_DIR) + "/inputs/" + name); }

const char* kShippedScenes[] = {"denlinger_flume.json", "denlinger_flume_abe2005.json", "denlinger_flume_mu_i.json",
                                "column_collapse_sand_mu_i.json", "column_collapse_mu_i.json", "elastic_block_slide.json",
                                "inclined_flow_bagnold.json", "benchmarks/sand_slide_incline.json",
                                "benchmarks/column_w12500.json", "benchmarks/column_w10000_compression.json",
                                "benchmarks/block_between_walls.json", "benchmarks/dynamic_bar.json",
                                "terrain/slope_to_runout_linear.json", "terrain/sand_slab_ramped.json",
                                "terrain/incline30_coarse.json", "terrain/horizontal_plane_fine.json"};

TEST(AuthoringWarnings, ABedRisingAlongXUnderTheRunoutDiagnosticsIsWarnedAbout) {
  const std::string rising = "diagnostics.runout on a bed that rises along +x under the bodies (grid.terrain: z = 45.6 m "
                             "at x = 92 m and 56.16 m at x = 112 m, the ends of their footprint)";
  EXPECT_EQ(warnings_with(parse_scene(kRising, "t"), rising), 1);
  EXPECT_EQ(warnings_with(parse_scene(kRising, "t"), "mirror the profile"), 1);
  EXPECT_EQ(warnings_with(parse_scene(kDescending, "t"), "rises along +x"), 0);
  // a valley whose far wall ends higher than the slide starts: the slide still runs along +x
  Scene valley = parse_scene(kDescending, "t");
  valley.grid.terrain.points = {{0.0, 60.0}, {60.0, 0.0}, {120.0, 70.0}};
  EXPECT_EQ(warnings_with(valley, "rises along +x"), 0);
  // without the runout diagnostics nothing is measured along +x
  Scene off = parse_scene(kRising, "t");
  off.runout.enabled = false;
  EXPECT_EQ(warnings_with(off, "rises along +x"), 0);
  // a flat grid whose gravity pulls along -x
  Scene flat = shipped("benchmarks/sand_slide_incline.json");
  EXPECT_EQ(warnings_with(flat, "runs along -x"), 0);
  flat.gravity[0] = -flat.gravity[0];
  EXPECT_EQ(warnings_with(flat, "diagnostics.runout with gravity[0] = -5.111104488356054 < 0 on a flat grid: the flow runs along -x"), 1);
  for (const char* name : kShippedScenes) EXPECT_EQ(warnings_with(shipped(name), "along -x"), 0) << name;
}

TEST(AuthoringWarnings, ValuesThatLookLikeTheWrongUnitAreWarnedAbout) {
  const auto warned = [](const std::string& from, const std::string& to, const std::string& what) {
    return warnings_with(parse_scene(replace_once(kDescending, from, to), "t"), what);
  };
  EXPECT_EQ(warned("\"density\": 1800", "\"density\": 1.8",
                   "materials.sand.density = 1.8 kg/m³ is below 100 kg/m³, lighter than any soil or rock: in g/cm³ or "
                   "t/m³? (1.8 g/cm³ is 1800 kg/m³)"), 1);
  EXPECT_EQ(warned("\"density\": 1800", "\"density\": 17658", "materials.sand.density"), 0);
  EXPECT_EQ(warned("\"density\": 1800", "\"density\": 176580", "materials.sand.density = 176580 kg/m³ is above 25000"), 1);
  EXPECT_EQ(warnings_with(parse_scene(kDescending, "t"), "materials.sand"), 0);
  // μ(I): d is in metres (0.5 mm sand: 0.0005)
  const std::string mu_i = R"("poisson": 0.3, "model": "mu_i", "grain_density": 2650, "grain_diameter": )";
  EXPECT_EQ(warned("\"poisson\": 0.3", mu_i + "0.5",
                   "materials.sand.grain_diameter = 0.5 m is a grain of 500 mm, above 0.05 m: in metres, not "
                   "millimetres?"), 1);
  EXPECT_EQ(warned("\"poisson\": 0.3", mu_i + "0.0005", "grain_diameter"), 0);
  EXPECT_EQ(warned("\"poisson\": 0.3", mu_i + "0.02", "grain_diameter"), 0);  // gravel
  // gravity on a terrain grid: tilted (the slope counted twice), up, or in cm/s²
  EXPECT_EQ(warned("\"time\"", "\"gravity\": [4.9, 0, -8.5], \"time\"",
                   "gravity = [4.9, 0, -8.5] on a terrain grid has a component along x or y: grid.terrain already tilts "
                   "the bed, so the slope is counted twice"), 1);
  EXPECT_EQ(warned("\"time\"", "\"gravity\": [0, 0, 9.81], \"time\"", "gravity[2] = 9.81 > 0 on a terrain grid points up"), 1);
  EXPECT_EQ(warned("\"time\"", "\"gravity\": [0, 0, -981], \"time\"",
                   "|gravity| = 981 m/s² on a terrain grid is far from 9.81 (outside [1, 50]): in cm/s²"), 1);
  EXPECT_EQ(warned("\"time\"", "\"gravity\": [0, 0, -0.0981], \"time\"", "far from 9.81"), 1);
  EXPECT_EQ(warnings_with(parse_scene(kDescending, "t"), "gravity"), 0);
  // (a flat grid with 200-250 m/s² along x, the column benchmarks in nondimensional units: none)
  for (const char* name : kShippedScenes) {
    const Scene s = shipped(name);
    EXPECT_EQ(warnings_with(s, "gravity"), 0) << name;
    EXPECT_EQ(warnings_with(s, "kg/m³ is"), 0) << name;
    EXPECT_EQ(warnings_with(s, "self-weight"), 0) << name;
  }
}

// A hunt's mistakes that no range refuses: a μ(I) solid fraction of 1 (density = grain_density) or 0.04
// (density 100), gravity pointing up on a flat grid, and μ(I) on a flat grid tilted beyond atan mu_2,
// where no steady flow exists. Each is one line; the shipped scenes get none of them.
TEST(AuthoringWarnings, AMuIPackingGravityUpAndAnInclineBeyondMu2AreWarnedAbout) {
  const Scene bagnold = shipped("inclined_flow_bagnold.json");  // glass beads, solid fraction 0.6, tan θ = 0.445
  for (const char* what : {"solid fraction", "points up", "accelerates without end"})
    EXPECT_EQ(warnings_with(bagnold, what), 0) << what;
  Scene packed = bagnold;
  packed.materials[0].density = 2450.0;
  EXPECT_EQ(warnings_with(packed, "materials.beads: density / grain_density = 2450 / 2450 = 1, the packing's solid "
                                  "fraction, is outside [0.5, 0.74]"),
            1);
  packed.materials[0].density = 100.0;
  EXPECT_EQ(warnings_with(packed, "density / grain_density = 100 / 2450 = 0.0408"), 1);
  packed.materials[0].density = 1250.0;  // 0.51
  EXPECT_EQ(warnings_with(packed, "solid fraction"), 0);
  Scene steep = bagnold;
  const double g = steep.gravity.norm(), theta = std::atan(0.7);
  steep.gravity = {g * std::sin(theta), 0.0, -g * std::cos(theta)};
  EXPECT_EQ(warnings_with(steep, "tilts the flat grid by 34.99 degrees: tan θ = 0.7 is above materials.beads.mu_2 = "
                                 "0.6435, the most friction μ(I) gives"),
            1);
  Scene up = shipped("benchmarks/sand_slide_incline.json");
  up.gravity[2] = 9.81;
  EXPECT_EQ(warnings_with(up, "gravity[2] = 9.81 > 0 on a flat grid points up"), 1);
  for (const char* name : kShippedScenes)
    for (const char* what : {"solid fraction", "points up", "accelerates without end"})
      EXPECT_EQ(warnings_with(shipped(name), what), 0) << name << ": " << what;
}

// young = 5e3 Pa for a 5 m slab of density 1800: rho g H / E = 18 (the first-step warning, about the
// step, says nothing here); 5e6 Pa: 0.018.
TEST(AuthoringWarnings, AModulusTooSoftForTheBodysWeightIsWarnedAbout) {
  const auto with_young = [](const std::string& young) {
    return parse_scene(replace_once(kDescending, "\"young\": 5e6", "\"young\": " + young), "t");
  };
  EXPECT_EQ(warnings_with(with_young("5e3"),
                          "bodies[0] (\"slab\"): its self-weight strain ρ g H / E = 17.7 (density 1800 kg/m³, |g| = "
                          "9.81 m/s², H = 5 m its extent along gravity, materials.sand.young = 5000 Pa) is above 0.1"),
            1);
  EXPECT_EQ(warnings_with(with_young("5e3"), "is longer than the"), 0);
  EXPECT_EQ(warnings_with(with_young("5e6"), "self-weight"), 0);
  EXPECT_EQ(warnings_with(with_young("8e5"), "self-weight"), 1);   // 0.11
  EXPECT_EQ(warnings_with(with_young("9e5"), "self-weight"), 0);   // 0.098
}

TEST(AuthoringWarnings, AGateInsideTheBodiesOrARunoutPlaneUpslopeOfItIsWarnedAbout) {
  const auto with_runout = [](const std::string& runout) {
    return parse_scene(replace_once(kDescending, "\"runout\": {}", "\"runout\": " + runout), "t");
  };
  EXPECT_EQ(warnings_with(with_runout(R"({ "gate_x": 10 })"),
                          "diagnostics.runout.gate_x = 10 lies inside the bodies' initial extent along x [8, 28]: the "
                          "runout from the gate counts the 18 m of the mass already beyond it"),
            1);
  EXPECT_EQ(warnings_with(with_runout(R"({ "gate_x": 28 })"), "gate_x"), 0);
  EXPECT_EQ(warnings_with(with_runout(R"({ "gate_x": 28, "runout_plane_x": 5 })"),
                          "diagnostics.runout.runout_plane_x = 5 is upslope of gate_x = 28"),
            1);
  EXPECT_EQ(warnings_with(with_runout(R"({ "gate_x": 28, "runout_plane_x": 90 })"), "upslope"), 0);
  // The flume's wedge rests on the bed over [-0.21, 0] and its free surface reaches x = 0.08 past the
  // gate foot at x = 0: the gate is at the end of its footprint, not inside it.
  for (const char* name : kShippedScenes) EXPECT_EQ(warnings_with(shipped(name), "diagnostics.runout."), 0) << name;
  Scene inside = shipped("denlinger_flume.json");
  inside.runout.gate_x = -0.1;
  EXPECT_EQ(warnings_with(inside, "gate_x = -0.1 lies inside the bodies' initial extent along x [-0.213388, 0]"), 1);
}

// docs/scene-reference.md, grid.terrain.radii: "put kinks on node columns or use r >= 2h".
TEST(AuthoringWarnings, AKinkBetweenNodeColumnsIsWarnedAbout) {
  Scene s = parse_scene(kDescending, "t");  // kinks at x = 25, 50, 70, 90 and h = 2: 25 lies between 24 and 26
  EXPECT_EQ(warnings_with(s, "grid.terrain.points[1] = (25, 48) is a sharp kink (radius 0) between the node columns "
                             "x = 24 and 26 m"), 1);
  EXPECT_EQ(warnings_with(s, "is a sharp kink"), 1);  // 50, 70 and 90 lie on node columns
  s.grid.terrain.radii = {0.0, 1.0, 0.0, 0.0, 0.0, 0.0};
  EXPECT_EQ(warnings_with(s, "grid.terrain.points[1] = (25, 48) is a transition of radius 1 m, below 2h = 4 m,"), 1);
  s.grid.terrain.radii = {0.0, 4.0, 0.0, 0.0, 0.0, 0.0};
  EXPECT_EQ(warnings_with(s, "grid.terrain.points[1]"), 0);
  // a slight bend between columns is cut by less than a transition of r = 2h departs: none
  s.grid.terrain.points = {{0.0, 60.0}, {25.0, 48.0}, {120.0, 0.5}};
  s.grid.terrain.radii.clear();
  EXPECT_EQ(warnings_with(s, "grid.terrain.points[1]"), 0);
  for (const char* name : kShippedScenes) EXPECT_EQ(warnings_with(shipped(name), "node columns x ="), 0) << name;
}

TEST(AuthoringWarnings, AMisspeltFaceKeyAndABoxOutsideTheGridNameTheKey) {
  test::expect_variant_error(kDescending, "\"friction_coefficient\": 0.5", "\"friction_coeff\": 0.5",
                             "unknown key boundaries.z-.friction_coeff (allowed here: type, friction_coefficient)");
  test::expect_variant_error(kDescending, "\"max\": [28, 2, 5]", "\"max\": [28, 2, 20]",
                             "bodies[0].box.max[2] = 20 (w, the height above the bed) lies outside the grid [0, 16]: the "
                             "box [0, 20] along axis 2 lies partly outside it");
  test::expect_variant_error(kDescending, "\"min\": [8, 0, 0]", "\"min\": [-130, 0, 0]",
                             "bodies[0].box.min[0] = -130 (x) lies outside the grid [0, 120]: the box [-130, 28] along axis "
                             "0 lies partly outside it");
  test::expect_variant_error(kDescending, "\"min\": [8, 0, 0], \"max\": [28, 2, 5]",
                             "\"min\": [130, 0, 0], \"max\": [140, 2, 5]",
                             "bodies[0].box.max[0] = 140 (x) lies outside the grid [0, 120]: the box [130, 140] along axis "
                             "0 lies wholly outside it");
}

// A warning factor at or above the stop's is never said: the row that passes it trips the guard first.
TEST(AuthoringWarnings, AnEnergyWarningThatTheGuardWouldAlwaysPreemptIsWarnedAbout) {
  const auto with_guards = [](const std::string& guards) {
    return parse_scene(replace_once(kDescending, "\"output\"", "\"guards\": " + guards + ", \"output\""), "t");
  };
  EXPECT_EQ(warnings_with(with_guards(R"({ "energy_warning_factor": 0.5, "energy_growth_factor": 0.2 })"),
                          "guards.energy_warning_factor = 0.5 is not below guards.energy_growth_factor = 0.2: the "
                          "energy guard stops the run before the warning could be said, so it never is"),
            1);
  EXPECT_EQ(warnings_with(with_guards(R"({ "energy_warning_factor": 0.2, "energy_growth_factor": 0.2 })"),
                          "guards.energy_warning_factor = 0.2 is not below guards.energy_growth_factor = 0.2"),
            1);
  EXPECT_EQ(warnings_with(with_guards(R"({ "energy_warning_factor": 1.5 })"),  // the stop's default, 1
                          "guards.energy_warning_factor = 1.5 is not below guards.energy_growth_factor = 1:"),
            1);
  EXPECT_EQ(warnings_with(with_guards(R"({ "energy_warning_factor": 0.1, "energy_growth_factor": 0.2 })"),
                          "energy_warning_factor"),
            0);
  EXPECT_EQ(warnings_with(with_guards(R"({ "energy_warning_factor": 0, "energy_growth_factor": 0.05 })"),  // off
                          "energy_warning_factor"),
            0);
  EXPECT_EQ(warnings_with(parse_scene(kDescending, "t"), "energy_warning_factor"), 0);  // the defaults, 0.1 and 1
  // the shipped scene that warns and then trips the guard by design
  EXPECT_EQ(warnings_with(shipped("terrain/energy_guard_kink.json"), "energy_warning_factor"), 0);
  for (const char* name : kShippedScenes) EXPECT_EQ(warnings_with(shipped(name), "energy_warning_factor"), 0) << name;
}

}  // namespace
}  // namespace authoring_warnings_test
}  // namespace talus
