#pragma once
// Small scenes shared by the solver tests, written as JSON so they read like the files in inputs/.
#include "talus/core/error.hpp"
#include "talus/particles/seeding.hpp"
#include "talus/scene/scene_json.hpp"

#include <fmt/core.h>
#include <gtest/gtest.h>

#include <optional>
#include <string>

namespace talus::test {

/// `text` with its first `from` replaced by `to` (a test failure if there is none): for making
/// one bad variant of a good scene text.
inline std::string replace_once(std::string text, const std::string& from, const std::string& to) {
  const auto at = text.find(from);
  EXPECT_NE(at, std::string::npos) << from;
  return text.replace(at, from.size(), to);
}

/// How many of the scene's warnings (scene_warnings, printed by run and check) hold `fragment`.
inline int warnings_with(const Scene& scene, const std::string& fragment) {
  int count = 0;
  for (const std::string& w : scene_warnings(scene)) count += w.find(fragment) != std::string::npos;
  return count;
}

/// How far scene_error_of takes a scene text: reading it, or reading it and seeding its bodies.
enum class SceneStage { Read, ReadAndSeed };

/// The message of the talus::Error that a bad scene text throws at `stage`, expected to be one
/// line (and, unless expected_exit_code is nullopt, to carry that exit code); a test failure if
/// nothing is thrown. For the tests of the messages that name the bad key.
inline std::string scene_error_of(const std::string& text, SceneStage stage = SceneStage::Read,
                                  std::optional<int> expected_exit_code = 2) {
  try {
    const Scene scene = parse_scene(text, "test.json");
    if (stage == SceneStage::ReadAndSeed) seed_particles(scene);
  } catch (const Error& e) {
    if (expected_exit_code) {
      EXPECT_EQ(e.exit_code(), *expected_exit_code);
    }
    const std::string what = e.what();
    EXPECT_EQ(what.find('\n'), std::string::npos) << "one line: " << what;
    return what;
  }
  ADD_FAILURE() << "no error for: " << text;
  return "";
}

/// Reading `good` with its first `from` replaced by `to` must fail with a message that contains
/// `expected` (and is one line, with exit code `exit_code` unless that is nullopt).
inline void expect_variant_error(const std::string& good, const std::string& from, const std::string& to,
                                 const std::string& expected, std::optional<int> exit_code = 2) {
  const std::string what = scene_error_of(replace_once(good, from, to), SceneStage::Read, exit_code);
  EXPECT_NE(what.find(expected), std::string::npos) << "with " << to << " for " << from << ": " << what;
}

/// A thin 3D bar along x (one cell across, slip side walls): the 1D problems of the papers.
/// Fixed at x = 0; initial velocity v0 along x; nu = 0 so that the wave speed is sqrt(E / rho).
inline Scene bar_scene(double length, double v0, int particles_per_cell = 2, double end_time = 0.04) {
  const std::string json = fmt::format(R"({{
    "name": "bar",
    "grid": {{ "origin": [0, 0, 0], "size": [{}, 1, 1], "cell_size": 1.0 }},
    "gravity": [0, 0, 0],
    "time": {{ "end": {}, "courant": 0.1 }},
    "materials": {{ "m": {{ "density": 1.0, "young": 1.0e6, "poisson": 0.0 }} }},
    "bodies": [ {{ "name": "bar", "material": "m", "box": {{ "min": [0, 0, 0], "max": [{}, 1, 1] }},
                  "particles_per_cell": {}, "velocity": [{}, 0, 0] }} ],
    "boundaries": {{ "x-": "fixed", "x+": "open", "y-": "slip", "y+": "slip", "z-": "slip", "z+": "slip" }}
  }})", length + 4.0, end_time, length, particles_per_cell, v0);
  return parse_scene(json, "bar_scene");
}

/// An elastic block in free fall, far from every wall.
inline Scene free_fall_scene(const char* scheme) {
  const std::string json = fmt::format(R"({{
    "name": "free_fall",
    "grid": {{ "origin": [0, 0, 0], "size": [0.4, 0.4, 1.6], "cell_size": 0.05 }},
    "time": {{ "end": 0.3, "courant": 0.3 }},
    "solver": {{ "scheme": "{}" }},
    "materials": {{ "m": {{ "density": 1000.0, "young": 1.0e6, "poisson": 0.3 }} }},
    "bodies": [ {{ "name": "block", "material": "m", "box": {{ "min": [0.1, 0.1, 1.2], "max": [0.3, 0.3, 1.4] }},
                  "particles_per_cell": 2 }} ],
    "boundaries": {{ "x-": "open", "x+": "open", "y-": "open", "y+": "open", "z-": "open", "z+": "open" }}
  }})", scheme);
  return parse_scene(json, "free_fall_scene");
}

/// A spinning, sheared block that hits a frictional floor: non-trivial stress in every component,
/// several blocks of particles, particles crossing cells and colour blocks.
inline Scene tumbling_block_scene(double end_time = 0.05) {
  const std::string json = fmt::format(R"({{
    "name": "tumbling",
    "grid": {{ "origin": [0, 0, 0], "size": [0.8, 0.6, 0.6], "cell_size": 0.025 }},
    "time": {{ "end": {}, "courant": 0.4 }},
    "materials": {{ "soft": {{ "density": 800.0, "young": 2.0e5, "poisson": 0.25 }},
                    "stiff": {{ "density": 2000.0, "young": 5.0e6, "poisson": 0.2 }} }},
    "bodies": [
      {{ "name": "a", "material": "soft", "box": {{ "min": [0.1, 0.1, 0.03], "max": [0.35, 0.3, 0.25] }},
         "particles_per_cell": 2, "velocity": [3.0, 0.5, -2.0] }},
      {{ "name": "b", "material": "stiff", "box": {{ "min": [0.4, 0.2, 0.1], "max": [0.6, 0.45, 0.3] }},
         "particles_per_cell": 2, "velocity": [-2.0, 0.0, -1.0] }} ],
    "boundaries": {{ "z-": {{ "type": "friction", "friction_coefficient": 0.4 }}, "z+": "open" }}
  }})", end_time);
  return parse_scene(json, "tumbling_block_scene");
}

/// Plane-strain collapse of a Drucker-Prager sand column (the half right of the symmetry wall
/// x = 0) onto a frictional floor: inputs/column_collapse_2d.json at a coarser cell.
inline Scene column_collapse_scene(double cell, double end_time, const char* extra_material_keys = "") {
  const std::string json = fmt::format(R"({{
    "name": "column_collapse",
    "grid": {{ "origin": [0, 0, 0], "size": [0.6, {}, 0.3], "cell_size": {} }},
    "time": {{ "end": {}, "courant": 0.3 }},
    "materials": {{ "sand": {{ "model": "drucker_prager", "density": 1600.0, "young": 2.0e6, "poisson": 0.3,
                               "friction_angle": 30.0, "dilatancy_angle": 0.0, "cohesion": 10.0{} }} }},
    "bodies": [ {{ "name": "column", "material": "sand", "box": {{ "min": [0, 0, 0], "max": [0.1, {}, 0.2] }},
                  "particles_per_cell": 2 }} ],
    "boundaries": {{ "x-": "slip", "x+": "slip", "y-": "slip", "y+": "slip",
                     "z-": {{ "type": "friction", "friction_coefficient": 0.5 }}, "z+": "open" }}
  }})", cell, cell, end_time, extra_material_keys, cell);
  return parse_scene(json, "column_collapse_scene");
}

}  // namespace talus::test
