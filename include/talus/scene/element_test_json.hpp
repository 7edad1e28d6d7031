#pragma once
// The element test's spec file (`talus element-test`, docs/drucker-prager.md): read with the scene's
// reader and the scene's rules; its "material" object has the same fields as a scene material with
// "model": "drucker_prager" (the default) or "mu_i" (docs/mu-i.md).
#include "talus/material/element_test.hpp"
#include "talus/material/mu_i_shear_test.hpp"

#include <nlohmann/json.hpp>

#include <string>

namespace talus {

/// A spec of either model: a Drucker-Prager path or the μ(I) steady simple shear ("mu_i_shear").
struct ElementTestRequest {
  enum class Model { DruckerPrager, MuI } model = Model::DruckerPrager;
  ElementTestSpec drucker_prager;  // model DruckerPrager
  MuIShearSpec mu_i;               // model MuI
};

/// Parse and validate a spec of either model. Throws talus::Error (input) naming the key path and
/// the allowed range.
ElementTestRequest parse_element_test_request(const std::string& text, const std::string& source);
ElementTestRequest read_element_test_request(const std::string& path);

/// Parse and validate a Drucker-Prager spec. Throws talus::Error (input) naming the key path and the allowed range.
ElementTestSpec parse_element_test(const std::string& text, const std::string& source);
ElementTestSpec read_element_test_file(const std::string& path);

/// The JSON Schema of a spec file (docs/element-test.schema.json is this, written by `talus schema`).
nlohmann::json element_test_json_schema();

}  // namespace talus
