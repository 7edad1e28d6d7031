#include "talus/scene/scene_schema.hpp"

#include "scene_fields.hpp"

namespace talus {

nlohmann::json scene_json_schema() {
  using scene_detail::Json;
  Json schema = {{"$schema", "http://json-schema.org/draft-07/schema#"},
                 {"title", "talus scene"},
                 {"description",
                  "A talus scene file (docs/scene-reference.md). Made by `talus schema` from the scene reader's field "
                  "tables; do not edit by hand."}};
  schema.update(scene_detail::schema_of(scene_detail::scene_table()));
  return schema;
}

std::string scene_reference_table() {
  std::string out = "| key | type | default | allowed | meaning |\n|---|---|---|---|---|\n";
  for (const auto& row : scene_detail::doc_rows(scene_detail::scene_table(), ""))
    out += fmt::format("| `{}` | {} | {} | {} | {} |\n", row[0], row[1], row[2], row[3], row[4]);
  return out;
}

}  // namespace talus
