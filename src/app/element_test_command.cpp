// `talus element-test SPEC.json --out FILE.csv`: single-point Drucker–Prager test along a
// strain- or mixed-controlled path (seed 001 sec. 6(3), Fig. 13). The spec format and the CSV
// columns are documented in docs/drucker-prager.md; the spec is read by the scene layer
// (scene/element_test_json.hpp), the driver is talus::run_element_test.
#include "commands.hpp"
#include "talus/core/error.hpp"
#include "talus/material/element_test.hpp"
#include "talus/scene/element_test_json.hpp"

#include <fmt/core.h>

#include <fstream>
#include <memory>
#include <string>

namespace talus::app {

namespace {

void run_element_test_command(const std::string& spec_file, const std::string& out_file) {
  const ElementTestSpec spec = read_element_test_file(spec_file);  // the scene's reader and rules
  const std::vector<ElementTestPoint> points = run_element_test(spec);

  std::ofstream out(out_file);
  if (!out) throw io_error(fmt::format("cannot write {}", out_file));
  write_element_test_csv(out, points);
  out.close();
  if (!out) throw io_error(fmt::format("error while writing {}", out_file));
  fmt::print("element-test: {} increments, final regime {}, wrote {}\n", points.size() - 1,
             regime_name(points.back().regime), out_file);
}

}  // namespace

void add_element_test_command(CLI::App& app) {
  CLI::App* cmd = app.add_subcommand(
      "element-test",
      "Single-point Drucker-Prager test (uniaxial compression, simple shear, drained triaxial, "
      "oedometer) from a JSON spec; writes a CSV. See docs/drucker-prager.md.");
  auto spec_file = std::make_shared<std::string>();
  auto out_file = std::make_shared<std::string>();
  cmd->add_option("spec", *spec_file, "JSON spec (material + path), e.g. inputs/element_tests/*.json")
      ->required();
  cmd->add_option("--out,-o", *out_file, "CSV file to write")->required();
  cmd->callback([spec_file, out_file] { run_element_test_command(*spec_file, *out_file); });
}

}  // namespace talus::app
