// Periodic faces in the scene file (docs/scene-reference.md "Boundaries"): the pairs they must come
// in, where they are refused, and the cell counts the colour blocks need; each a one-line error
// naming the key.
#include "../solver/scene_fixtures.hpp"
#include "talus/scene/scene_json.hpp"

#include <gtest/gtest.h>

#include <string>

namespace talus {
namespace periodic_scene_test {
namespace {

const char* kPeriodic = R"({
  "grid": { "size": [0.8, 0.8, 0.4], "cell_size": 0.1 },
  "time": { "end": 0.1 },
  "materials": { "m": { "density": 1000, "young": 1e6, "poisson": 0.3 } },
  "bodies": [ { "name": "b", "material": "m", "box": { "min": [0, 0, 0], "max": [0.3, 0.3, 0.2] } } ],
  "boundaries": { "x-": "periodic", "x+": "periodic", "y-": "periodic", "y+": "periodic", "z-": "fixed" }
})";

TEST(PeriodicScene, PairedFacesSetThePeriodicAxes) {
  const Scene s = parse_scene(kPeriodic, "t");
  EXPECT_TRUE(s.grid.periodic[0]);
  EXPECT_TRUE(s.grid.periodic[1]);
  EXPECT_FALSE(s.grid.periodic[2]);
  EXPECT_EQ(s.walls[0][1].type, WallType::Periodic);
  const Scene again = parse_scene(scene_to_json(s).dump(), "again");  // the resolved scene reads back
  EXPECT_EQ(scene_to_json(again), scene_to_json(s));
  EXPECT_TRUE(again.grid.periodic[0]);
}

TEST(PeriodicScene, BadUseNamesTheKey) {
  const std::string ok = kPeriodic;
  test::expect_variant_error(ok, "\"x+\": \"periodic\"", "\"x+\": \"slip\"",
                             "boundaries.x+ = \"slip\": must be \"periodic\" like boundaries.x- (periodic faces come in pairs)");
  test::expect_variant_error(ok, "\"y-\": \"periodic\"", "\"y-\": \"open\"",
                             "boundaries.y- = \"open\": must be \"periodic\" like boundaries.y+");
  test::expect_variant_error(ok, "\"z-\": \"fixed\"", "\"z-\": \"periodic\"",
                             "boundaries.z- = \"periodic\": only the x and y faces can be periodic");
  test::expect_variant_error(ok, "\"size\": [0.8, 0.8, 0.4]", "\"size\": [0.6, 0.8, 0.4]",
                             "grid.cells[0] = 6 with periodic x faces: must be 4 or a multiple of 8");
  // the wider supports use blocks of 8: 8 cells are one block, 12 are refused
  const std::string bspline = test::replace_once(ok, "\"time\"", "\"solver\": { \"shape\": \"bspline2\" }, \"time\"");
  EXPECT_NO_THROW(parse_scene(bspline, "t"));
  test::expect_variant_error(bspline, "\"size\": [0.8, 0.8, 0.4]", "\"size\": [1.2, 0.8, 0.4]",
                             "grid.cells[0] = 12 with periodic x faces: must be 8 or a multiple of 16");
  test::expect_variant_error(ok, "\"time\"", "\"solver\": { \"smoothing\": {} }, \"time\"",
                             "boundaries.x- = \"periodic\" cannot run with solver.smoothing");
  // the runout is measured along x, where a periodic flow wraps (it read a front 0.1 m past the gate)
  test::expect_variant_error(ok, "\"time\"", "\"diagnostics\": { \"runout\": {} }, \"time\"",
                             "diagnostics.runout cannot run with periodic x faces");
  test::expect_variant_error(test::replace_once(ok, "\"x-\": \"periodic\", \"x+\": \"periodic\", ", ""), "\"time\"",
                             "\"diagnostics\": { \"runout\": { \"gate_x\": 1e20 } }, \"time\"",
                             "diagnostics.runout.gate_x = 1e+20 is outside the grid along x, [0, 0.8]");
  test::expect_variant_error(test::replace_once(ok, "\"x-\": \"periodic\", \"x+\": \"periodic\", ", ""), "\"time\"",
                             "\"diagnostics\": { \"runout\": { \"runout_plane_x\": -0.8 } }, \"time\"",
                             "diagnostics.runout.runout_plane_x = -0.8 is outside the grid along x, [0, 0.8]");
  test::expect_variant_error(ok, "\"time\"", "\"solver\": { \"scatter\": \"block_buffers\" }, \"time\"",
                             "boundaries.x- = \"periodic\" cannot run with solver.scatter = \"block_buffers\"");
  test::expect_variant_error(ok, "\"time\"", "\"solver\": { \"scatter\": \"blocks\" }, \"time\"",
                             "solver.scatter = \"blocks\" is not one of: colour_passes, block_buffers");
  test::expect_variant_error(ok, "\"cell_size\": 0.1 }", "\"cell_size\": 0.1, \"terrain\": { \"points\": [[0, 0], [0.8, -0.1]] } }",
                             "boundaries.x- = \"periodic\" needs a flat grid");
  // y alone periodic on a terrain grid: accepted before, against the docs, and never tested
  const std::string y_only = test::replace_once(ok, "\"x-\": \"periodic\", \"x+\": \"periodic\"", "\"x-\": \"slip\", \"x+\": \"slip\"");
  test::expect_variant_error(y_only, "\"cell_size\": 0.1 }", "\"cell_size\": 0.1, \"terrain\": { \"points\": [[0, 0], [0.8, -0.1]] } }",
                             "boundaries.y- = \"periodic\" needs a flat grid: grid.terrain is set (periodic faces are not "
                             "verified on a terrain grid)");
  test::expect_variant_error(ok, "\"x-\": \"periodic\"", "\"x-\": \"periodical\"",
                             "boundaries.x- = \"periodical\" is not one of: open, slip, fixed, friction, periodic");
}

TEST(PeriodicScene, BlockCellsChangeTheCellCountsAllowed) {
  // 3-cell blocks (linear): 6 cells make 2 blocks, 3 cells one, 9 cells 3 (odd: refused)
  const std::string three = test::replace_once(kPeriodic, "\"time\"", "\"solver\": { \"block_cells\": 3 }, \"time\"");
  const std::string six = test::replace_once(three, "\"size\": [0.8, 0.8, 0.4]", "\"size\": [0.6, 0.3, 0.4]");
  EXPECT_NO_THROW(parse_scene(six, "t"));
  test::expect_variant_error(six, "\"size\": [0.6, 0.3, 0.4]", "\"size\": [0.9, 0.3, 0.4]",
                             "grid.cells[0] = 9 with periodic x faces: must be 3 or a multiple of 6");
}

}  // namespace
}  // namespace periodic_scene_test
}  // namespace talus
