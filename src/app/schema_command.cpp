// `talus schema [--markdown | --element-test]`: what the input readers accept, printed from their
// field tables (src/scene/scene_fields.cpp). docs/scene.schema.json, docs/element-test.schema.json
// and the key table of docs/scene-reference.md are this command's output; the ctest
// SceneSchema.DocsMatchTheCode fails when they differ.
#include "commands.hpp"
#include "talus/scene/element_test_json.hpp"
#include "talus/scene/scene_schema.hpp"

#include <fmt/core.h>

#include <memory>

namespace talus::app {

void add_schema_command(CLI::App& app) {
  CLI::App* cmd = app.add_subcommand(
      "schema", "Print the JSON Schema of scene files (for editors and other tools), or the key table of "
                "docs/scene-reference.md");
  auto markdown = std::make_shared<bool>(false);
  auto element_test = std::make_shared<bool>(false);
  CLI::Option* table = cmd->add_flag("--markdown", *markdown, "The Markdown table of every scene key instead");
  // (element-test specs have no Markdown table: docs/drucker-prager.md section 6 shows a spec)
  cmd->add_flag("--element-test", *element_test, "The JSON Schema of `talus element-test` specs instead")->excludes(table);
  cmd->callback([markdown, element_test] {
    if (*markdown)
      fmt::print("{}", scene_reference_table());
    else
      fmt::print("{}\n", (*element_test ? element_test_json_schema() : scene_json_schema()).dump(2));
  });
}

}  // namespace talus::app
