// The scene reader: defaults, round trip, and one clear message per kind of bad input.
#include "scene_fixtures.hpp"
#include "talus/core/error.hpp"
#include "talus/scene/scene_json.hpp"
#include "talus/solver/solver.hpp"

#include <gtest/gtest.h>

namespace talus {
namespace {

const char* kMinimal = R"({
  "grid": { "size": [1, 1, 1], "cell_size": 0.1 },
  "time": { "end": 0.1 },
  "materials": { "m": { "density": 1000, "young": 1e6, "poisson": 0.3 } },
  "bodies": [ { "name": "b", "material": "m", "box": { "min": [0.2, 0.2, 0.2], "max": [0.5, 0.5, 0.5] } } ]
})";

using test::replace_once;

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
  test::expect_variant_error(ok, "\"cell_size\": 0.1", "\"cell_size\": 0.3", "grid.size[0] = 1 must be a positive whole multiple of grid.cell_size");
  test::expect_variant_error(ok, "\"young\": 1e6", "\"young\": 0", "materials.m.young");
  EXPECT_NE(error_of("{ \"grid\": ").find("malformed JSON"), std::string::npos);
  test::expect_variant_error(ok, "\"time\"", "\"solver\": { \"scheme\": \"rk4\" }, \"time\"", "solver.scheme = \"rk4\" is not one of: musl, usl");
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

}  // namespace
}  // namespace talus
