// Bad input (issue 9, item 3): each mistake gives one input Error naming the key path (and the
// allowed range where there is one); nothing is half-accepted.
#include "talus/core/error.hpp"
#include "talus/scene/scene_json.hpp"

#include <gtest/gtest.h>

#include <string>
#include <vector>

namespace talus {
namespace bad_input_test {
namespace {

const std::string kValid = R"({
  "name": "valid",
  "grid": { "origin": [0, 0, 0], "size": [1.0, 0.4, 0.4], "cell_size": 0.05 },
  "time": { "end": 0.1, "courant": 0.3 },
  "materials": { "rubber": { "density": 1000.0, "young": 1.0e6, "poisson": 0.3 },
                 "sand": { "model": "drucker_prager", "density": 1600.0, "young": 2.0e6, "poisson": 0.3,
                           "friction_angle": 30.0, "dilatancy_angle": 5.0 } },
  "bodies": [ { "name": "block", "material": "rubber", "box": { "min": [0.1, 0.1, 0.0], "max": [0.3, 0.3, 0.2] } },
              { "name": "heap", "material": "sand", "box": { "min": [0.5, 0.1, 0.0], "max": [0.7, 0.3, 0.2] } } ],
  "output": { "checkpoint_interval": 0.05 },
  "guards": { "energy_growth_factor": 2.0 }
})";

struct Case {
  const char* what;
  const char* from;  // replaced text (first occurrence) ...
  const char* to;    // ... by this
  const char* expect;  // the message must contain this (the key path, the range)
};

TEST(BadInput, EveryMistakeNamesTheKeyPathInOneLine) {
  ASSERT_NO_THROW(parse_scene(kValid, "valid"));
  const std::vector<Case> cases = {
      {"malformed JSON", "\"time\": {", "\"time\": {,", "malformed JSON"},
      {"truncated", "\"guards\"", "\"gua", "malformed JSON"},
      {"number overflowing to Inf", "\"end\": 0.1", "\"end\": 1e999", "malformed JSON: number overflow parsing '1e999' at line 4, column 20"},
      // the same text earlier inside a string is not the number that overflowed
      {"overflow placed past a string that quotes it",
       "\"valid\",\n  \"grid\": { \"origin\": [0, 0, 0], \"size\": [1.0, 0.4, 0.4], \"cell_size\": 0.05 },\n  \"time\": { \"end\": 0.1",
       "\"valid\", \"description\": \"end at 1e999\",\n  \"grid\": { \"origin\": [0, 0, 0], \"size\": [1.0, 0.4, 0.4], \"cell_size\": 0.05 },\n  \"time\": { \"end\": 1e999",
       "malformed JSON: number overflow parsing '1e999' at line 4, column 20"},
      {"negative overflow", "\"end\": 0.1", "\"end\": -1e999", "at line 4, column 20"},
      {"unknown key", "\"courant\": 0.3", "\"courant\": 0.3, \"courrant\": 0.3", "unknown key time.courrant"},
      {"wrong type", "\"young\": 1.0e6", "\"young\": \"1e6\"", "materials.rubber.young must be a number in (0, inf)"},
      {"negative", "\"density\": 1000.0", "\"density\": -1000.0", "materials.rubber.density = -1000 is outside the allowed range (0"},
      {"zero", "\"cell_size\": 0.05", "\"cell_size\": 0", "grid.cell_size = 0 is outside the allowed range (0"},
      {"nu = 0.5", "\"poisson\": 0.3", "\"poisson\": 0.5", "materials.rubber.poisson = 0.5 is outside the allowed range (-1, 0.5)"},
      {"phi = 0", "\"friction_angle\": 30.0", "\"friction_angle\": 0", "materials.sand.friction_angle"},
      {"phi = 90", "\"friction_angle\": 30.0", "\"friction_angle\": 90", "materials.sand.friction_angle"},
      {"psi > phi", "\"dilatancy_angle\": 5.0", "\"dilatancy_angle\": 35.0", "materials.sand.dilatancy_angle"},
      {"body outside the grid", "\"max\": [0.3, 0.3, 0.2]", "\"max\": [0.3, 0.3, 0.6]", "bodies[0].box"},
      {"empty body", "\"max\": [0.3, 0.3, 0.2]", "\"max\": [0.3, 0.3, 0.0]", "bodies[0].box.min[2] = 0 must be below max[2] = 0"},
      {"Courant = 1", "\"courant\": 0.3", "\"courant\": 1.0", "time.courant = 1 is outside the allowed range (0, 1)"},
      {"checkpoint interval negative", "\"checkpoint_interval\": 0.05", "\"checkpoint_interval\": -1", "output.checkpoint_interval"},
      {"guard factor zero", "\"energy_growth_factor\": 2.0", "\"energy_growth_factor\": 0", "guards.energy_growth_factor = 0"},
      {"grid too large", "\"size\": [1.0, 0.4, 0.4], \"cell_size\": 0.05", "\"size\": [1000, 1000, 1000], \"cell_size\": 0.05",
       "at most 1e9"},
      {"key with a newline", "\"courant\": 0.3", "\"courant\": 0.3, \"a\\nb\": 1", "unknown key time.a\\nb"},
      // nlohmann keeps a duplicate key's last value: the run would have used end = 5000 unannounced
      {"duplicate key", "\"end\": 0.1", "\"end\": 0.1, \"end\": 5000", "duplicate key time.end"},
      {"duplicate key in an array's object", "\"material\": \"sand\",", "\"material\": \"sand\", \"material\": \"sand\",",
       "duplicate key bodies[1].material"},
      {"duplicate material", "\"rubber\": {", "\"sand\": {}, \"rubber\": {", "duplicate key materials.sand"},
      {"duplicate body name", "\"name\": \"heap\"", "\"name\": \"block\"",
       "bodies[1].name = \"block\" is the name of bodies[0] as well"},
      // values within their ranges that leave no time step (the run stopped at step 0 naming nothing)
      {"subnormal density", "\"density\": 1000.0", "\"density\": 1e-320",
       "bodies[0] (\"block\"): no time step resolves its wave speed sqrt(M / materials.rubber.density) = inf m/s"},
      {"overflowing speed", "\"material\": \"rubber\",", "\"material\": \"rubber\", \"velocity\": [1e300, 1e300, 0],",
       "bodies[0].velocity[0] = 1e+300 is outside the allowed range"},
      // the message says which limit a number broke, and shows it as written
      {"beyond 1e30", "\"young\": 1.0e6", "\"young\": 1e308",
       "materials.rubber.young = 1e+308 is outside the allowed range (0, 1e+30] (magnitudes above 1e30 are refused)"},
      // a key whose range its material checks: the key's own range, not the reader's [-1e30, 1e30]
      {"angle beyond 1e30", "\"friction_angle\": 30.0", "\"friction_angle\": 1e31",
       "materials.sand.friction_angle = 1e+31 is outside the allowed range (0, 90)"},
      {"angle not a number", "\"friction_angle\": 30.0", "\"friction_angle\": \"30\"",
       "materials.sand.friction_angle must be a number in (0, 90), got \"30\""},
      {"vector beyond 1e30", "\"material\": \"rubber\",", "\"material\": \"rubber\", \"velocity\": [0, 0, -1e308],",
       "bodies[0].velocity[2] = -1e+308 is outside the allowed range [-1e+30, 1e+30] (magnitudes above 1e30 are refused)"},
      {"integer past 2^64", "\"courant\": 0.3", "\"courant\": 0.3, \"max_steps\": 18446744073709551615",
       "time.max_steps = 18446744073709551615 is outside the allowed range"},
      // the name is a folder under runs/ whose files a run replaces and clears
      {"name ..", "\"name\": \"valid\"", "\"name\": \"..\"", "name = \"..\" must be a plain folder name"},
      {"name with a slash", "\"name\": \"valid\"", "\"name\": \"../x\"", "name = \"../x\" must be a plain folder name"},
      {"empty name", "\"name\": \"valid\"", "\"name\": \"\"", "name = \"\" must be a plain folder name"},
      {"name with a newline", "\"name\": \"valid\"", "\"name\": \"a\\nb\"", "name = \"a\\nb\" must be a plain folder name"},
  };
  for (const Case& c : cases) {
    std::string text = kValid;
    const auto at = text.find(c.from);
    ASSERT_NE(at, std::string::npos) << c.what;
    text.replace(at, std::string(c.from).size(), c.to);
    try {
      parse_scene(text, "scene.json");
      ADD_FAILURE() << c.what << ": accepted";
    } catch (const Error& e) {
      EXPECT_EQ(e.kind(), Error::Kind::Input) << c.what;
      const std::string m = e.what();
      EXPECT_NE(m.find(c.expect), std::string::npos) << c.what << ": " << m;
      EXPECT_EQ(m.find('\n'), std::string::npos) << c.what << ": " << m;
    }
  }
  try {
    read_scene_file("/nonexistent/scene.json");
    ADD_FAILURE() << "missing file accepted";
  } catch (const Error& e) {
    EXPECT_EQ(e.kind(), Error::Kind::Input);
    EXPECT_NE(std::string(e.what()).find("cannot open scene file /nonexistent/scene.json: no such file"), std::string::npos);
  }
  try {
    read_scene_file("/");  // a folder: reading it gave an empty text
    ADD_FAILURE() << "a folder accepted";
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find("cannot open scene file /: it is a folder, not a file"), std::string::npos) << e.what();
  }
  try {
    parse_scene(kValid + std::string(1, '\0') + "{ junk", "scene.json");  // the parser stopped at the NUL
    ADD_FAILURE() << "text after a NUL byte passed unread";
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find("scene.json: malformed JSON: a NUL byte at offset"), std::string::npos) << e.what();
  }
}

}  // namespace
}  // namespace bad_input_test
}  // namespace talus
