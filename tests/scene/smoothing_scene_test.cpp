// MLS smoothing in the scene file (docs/scene-reference.md `solver.smoothing`): the fit variant, and
// where smoothing is refused, each a one-line error naming the key.
#include "../solver/scene_fixtures.hpp"
#include "talus/scene/scene.hpp"
#include "talus/scene/scene_json.hpp"

#include <gtest/gtest.h>

#include <string>

namespace talus {
namespace smoothing_scene_test {
namespace {

const char* kSmoothed = R"({
  "grid": { "size": [0.8, 0.8, 0.4], "cell_size": 0.1 },
  "time": { "end": 0.1 },
  "solver": { "smoothing": { "basis": "linear", "variant": "cell" } },
  "materials": { "m": { "density": 1000, "young": 1e6, "poisson": 0.3 } },
  "bodies": [ { "name": "b", "material": "m", "box": { "min": [0, 0, 0], "max": [0.3, 0.3, 0.2] } } ]
})";

TEST(SmoothingScene, TheFitVariantIsReadAndWrittenBack) {
  const Scene s = parse_scene(kSmoothed, "t");
  EXPECT_TRUE(s.smoothing.enabled);
  EXPECT_EQ(s.smoothing.mls.variant, MlsVariant::Cell);
  const Scene again = parse_scene(scene_to_json(s).dump(), "again");
  EXPECT_EQ(again.smoothing.mls.variant, MlsVariant::Cell);
  const Scene by_default =
      parse_scene(test::replace_once(kSmoothed, ", \"variant\": \"cell\"", ""), "default");
  EXPECT_EQ(by_default.smoothing.mls.variant, MlsVariant::Particle);  // the reference fit
}

TEST(SmoothingScene, TheCellFitIsWarnedAbout) {
  const auto warned = [](const Scene& s) { return test::warnings_with(s, "variant = \"cell\" is not energy-stable") > 0; };
  EXPECT_TRUE(warned(parse_scene(kSmoothed, "t")));
  EXPECT_FALSE(warned(parse_scene(test::replace_once(kSmoothed, "\"cell\"", "\"particle\""), "t")));
  EXPECT_FALSE(warned(parse_scene(test::replace_once(kSmoothed, "\"basis\"", "\"enabled\": false, \"basis\""), "t")));
}

TEST(SmoothingScene, BadUseNamesTheKey) {
  const std::string ok = kSmoothed;
  test::expect_variant_error(ok, "\"variant\": \"cell\"", "\"variant\": \"node\"",
                             "solver.smoothing.variant = \"node\" is not one of: particle, cell");
  test::expect_variant_error(ok, "\"cell_size\": 0.1 }",
                             "\"cell_size\": 0.1, \"terrain\": { \"points\": [[0, 0], [0.8, -0.1]] } }",
                             "solver.smoothing cannot run on a terrain grid");
  // switched off, the settings may stay on a terrain grid
  const std::string off = test::replace_once(ok, "\"basis\": \"linear\"", "\"enabled\": false, \"basis\": \"linear\"");
  EXPECT_NO_THROW(parse_scene(test::replace_once(off, "\"cell_size\": 0.1 }",
                                                 "\"cell_size\": 0.1, \"terrain\": { \"points\": [[0, 0], [0.8, -0.1]] } }"),
                              "t"));
}

}  // namespace
}  // namespace smoothing_scene_test
}  // namespace talus
