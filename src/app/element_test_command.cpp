// `talus element-test SPEC.json --out FILE.csv`: single-point Drucker–Prager test along a
// strain- or mixed-controlled path (Abe, Johansson & Konagai 2005, sec. 6(3), Fig. 13). The spec format and the CSV
// columns are documented in docs/drucker-prager.md; the spec is read by the scene layer
// (scene/element_test_json.hpp), the driver is talus::run_element_test.
// A spec whose material has "model": "mu_i" runs the μ(I) steady simple shear instead
// (talus::run_mu_i_shear_test; spec and columns in docs/mu-i.md).
#include "commands.hpp"
#include "option_checks.hpp"
#include "talus/core/error.hpp"
#include "talus/driver/warning.hpp"
#include "talus/material/element_test.hpp"
#include "talus/io/atomic_file.hpp"
#include "talus/material/mu_i_shear_test.hpp"
#include "talus/scene/element_test_json.hpp"

#include <fmt/core.h>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <memory>
#include <sstream>
#include <string>

namespace talus::app {

namespace {

/// The CSV that `write` produces, written through a temporary file and a rename: a test stopped
/// mid-write (a 1e7-increment path writes hundreds of MB) left a truncated CSV under its name, and
/// the earlier CSV was gone before the new one was complete.
template <class Write>
void write_csv(const std::string& out_file, Write write) {
  std::ostringstream text;
  write(text);
  write_file_atomically(out_file, text.str());
}

/// The largest |tau/p / mu(I) - 1| the mu(I) element test passes with: the target docs/mu-i.md §5 states
/// (the shipped spec reaches 3.3e-16).
constexpr double kMuIShearTolerance = 1e-10;

void run_mu_i_test_command(const MuIShearSpec& spec, const std::string& out_file) {
  const std::vector<MuIShearPoint> points = run_mu_i_shear_test(spec);
  if (const std::string shortfall = mu_i_shear_strain_shortfall(spec); !shortfall.empty())
    warn("{}", shortfall);
  write_csv(out_file, [&](std::ostream& out) { write_mu_i_shear_csv(out, points); });
  const MuIShearPoint* worst = nullptr;  // the first NaN, else the largest error
  for (const MuIShearPoint& p : points)
    if (!worst || !(std::abs(p.relative_error) <= std::abs(worst->relative_error))) {
      worst = &p;
      if (std::isnan(p.relative_error)) break;
    }
  const double largest = worst ? std::abs(worst->relative_error) : 0.0;
  fmt::print("element-test: mu(I) simple shear at {} inertial number{}, largest |tau/p / mu(I) - 1| = {:.2e}, wrote {}\n",
             points.size(), points.size() == 1 ? "" : "s", largest, out_file);
  // mu_2 = 1e6 or p = 1e8 Pa (the shipped strain) wrote tau/p up to 99% below mu(I) with exit code 0.
  if (worst && !(largest <= kMuIShearTolerance))
    throw instability_error(fmt::format(
        "element-test: mu(I) simple shear: |tau/p / mu(I) - 1| = {:.3g} at I = {:.6g} (tau/p = {:.6g}, mu(I) = {:.6g}) is "
        "above the tolerance {}: the sample had not reached steady flow (|d tau|/tau in its last increment: {:.3g}); the "
        "CSV is kept in {} to look at; more path.increments or a larger path.strain_increment reach it (docs/mu-i.md "
        "§5)",
        largest, worst->inertial_number, worst->friction, worst->friction_analytic, kMuIShearTolerance,
        worst->last_change, out_file));
}

void run_element_test_command(const std::string& spec_file, const std::string& out_file) {
  check_writable_file(out_file, "--out");
  // The CSV would replace the spec it was computed from.
  std::error_code ec;
  if (std::filesystem::equivalent(spec_file, out_file, ec))
    throw input_error(fmt::format("--out {} is the spec file itself; write the CSV to another file", out_file));
  const ElementTestRequest request = read_element_test_request(spec_file);  // the scene's reader and rules
  if (request.model == ElementTestRequest::Model::MuI) return run_mu_i_test_command(request.mu_i, out_file);
  const ElementTestSpec& spec = request.drucker_prager;
  // 1e7 increments (the largest allowed) took 2.5 minutes, 6.3 GB of memory and a 2.3 GB CSV without
  // a word: say so before (about 230 B a row on disk, 630 B an increment held while it runs).
  if (spec.increments > 1000000)
    warn("path.increments = {}: the CSV will take about {:.2g} GB and the test about {:.2g} GB of memory while it runs",
         spec.increments, 230e-9 * spec.increments, 630e-9 * spec.increments);
  const std::vector<ElementTestPoint> points = run_element_test(spec);

  write_csv(out_file, [&](std::ostream& out) { write_element_test_csv(out, points); });
  fmt::print("element-test: {} increments, final regime {}, wrote {}\n", points.size() - 1,
             regime_name(points.back().regime), out_file);
}

}  // namespace

void add_element_test_command(CLI::App& app) {
  CLI::App* cmd = app.add_subcommand(
      "element-test",
      "Single-point Drucker-Prager test (uniaxial compression, simple shear, drained triaxial, "
      "oedometer) or mu(I) steady simple shear from a JSON spec; writes a CSV. See "
      "docs/drucker-prager.md, docs/mu-i.md.");
  auto spec_file = std::make_shared<std::string>();
  auto out_file = std::make_shared<std::string>();
  cmd->add_option("spec", *spec_file, "JSON spec (material + path), e.g. inputs/element_tests/*.json")
      ->required();
  refuse_empty(cmd->add_option("--out,-o", *out_file, "CSV file to write")->required(), "give the CSV file to write");
  cmd->callback([spec_file, out_file] { run_element_test_command(*spec_file, *out_file); });
}

}  // namespace talus::app
