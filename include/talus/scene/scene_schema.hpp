#pragma once
// What the scene's field tables (src/scene/scene_fields.cpp) say about the file format, for people
// and other tools: the JSON Schema (docs/scene.schema.json) and the reference table of
// docs/scene-reference.md. `talus schema` prints both; a test checks the committed files.
#include <nlohmann/json.hpp>

#include <string>

namespace talus {

nlohmann::json scene_json_schema();

/// The Markdown table of every key (key path, type, default, allowed, meaning).
std::string scene_reference_table();

}  // namespace talus
