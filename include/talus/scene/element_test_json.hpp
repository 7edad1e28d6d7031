#pragma once
// The element test's spec file (`talus element-test`, docs/drucker-prager.md): read with the scene's
// reader and the scene's rules; its "material" object has the same Drucker-Prager fields as a
// scene material with "model": "drucker_prager".
#include "talus/material/element_test.hpp"

#include <nlohmann/json.hpp>

#include <string>

namespace talus {

/// Parse and validate a spec. Throws talus::Error (input) naming the key path and the allowed range.
ElementTestSpec parse_element_test(const std::string& text, const std::string& source);
ElementTestSpec read_element_test_file(const std::string& path);

/// The JSON Schema of a spec file (docs/element-test.schema.json is this, written by `talus schema`).
nlohmann::json element_test_json_schema();

}  // namespace talus
