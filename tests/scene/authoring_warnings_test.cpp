// Mistakes of a user writing a landslide scene of their own that no range refuses: a bed rising
// along +x under the runout diagnostics, values in another unit than the key's, a gate inside the
// mass, a kink between node columns; and the messages of two errors they met.
#include "../solver/scene_fixtures.hpp"
#include "talus/scene/scene_json.hpp"

#include <gtest/gtest.h>

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
  const std::string rising = "diagnostics.runout on a bed that rises along +x (grid.terrain: z = 0 m at the grid's x- "
                             "end, x = 0 m, and z = 60 m at its x+ end, x = 120 m)";
  EXPECT_EQ(warnings_with(parse_scene(kRising, "t"), rising), 1);
  EXPECT_EQ(warnings_with(parse_scene(kRising, "t"), "mirror the profile"), 1);
  EXPECT_EQ(warnings_with(parse_scene(kDescending, "t"), "rises along +x"), 0);
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

}  // namespace
}  // namespace authoring_warnings_test
}  // namespace talus
