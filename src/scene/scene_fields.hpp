#pragma once
// The tables of the scene file's sections (field_table.hpp): scene_json.cpp reads and writes
// through them, scene_schema.cpp makes the JSON Schema and the docs table from them, and the
// element test reads its material with the same Drucker-Prager fields.
#include "field_table.hpp"
#include "talus/scene/scene.hpp"

#include <map>
#include <string>
#include <vector>

namespace talus::scene_detail {

/// A scene while it is read: the Scene and what is resolved only at the end (body names that
/// solver.smoothing.bodies refers to, material names that bodies refer to).
struct SceneDraft {
  Scene scene;
  std::vector<std::string> smoothing_bodies;
  std::map<std::string, int> material_index;
};

/// The whole scene file, top level first; its object-valued keys carry their sections' tables.
const Table<SceneDraft>& scene_table();

/// The Drucker-Prager constants (young, poisson, friction_angle, ..., cone), with the check of the
/// DruckerPrager constructor: the element test's "material" object. The scene's materials use the
/// same fields (model "drucker_prager").
const Table<DruckerPragerParameters>& drucker_prager_table();

/// The μ(I) constants (young, poisson, mu_s, mu_2, i0, grain_diameter, grain_density), with the
/// check of the MuI constructor: the element test's "material" object for "model": "mu_i". The
/// scene's materials use the same fields (model "mu_i").
const Table<MuIParameters>& mu_i_table();

}  // namespace talus::scene_detail
