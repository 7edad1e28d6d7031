// `talus element-test SPEC.json --out FILE.csv`: single-point Drucker–Prager test along a
// strain- or mixed-controlled path (seed 001 sec. 6(3), Fig. 13). The spec format and the CSV
// columns are documented in docs/drucker-prager.md; the driver is talus::run_element_test.
// A spec whose material has "model": "mu_i" runs the μ(I) steady simple shear instead
// (talus::run_mu_i_shear_test; spec and columns in docs/mu-i.md).
#include "commands.hpp"
#include "talus/core/error.hpp"
#include "talus/material/element_test.hpp"
#include "talus/material/mu_i_shear_test.hpp"

#include <fmt/core.h>
#include <nlohmann/json.hpp>

#include <cmath>
#include <fstream>
#include <initializer_list>
#include <memory>
#include <string>
#include <string_view>

namespace talus::app {

namespace {

using nlohmann::json;

// Reads one JSON spec into ElementTestSpec; every error names the key path and allowed range.
class SpecReader {
 public:
  explicit SpecReader(std::string file) : file_(std::move(file)) {}

  ElementTestSpec read(const json& root) const {
    require_object(root, "");
    check_keys(root, "", {"description", "material", "path"});
    if (root.contains("description") && !root["description"].is_string())
      fail("description must be a string");
    ElementTestSpec spec;
    spec.material = material(member(root, "", "material"));
    read_path(member(root, "", "path"), spec);
    return spec;
  }

 private:
  std::string file_;

  [[noreturn]] void fail(const std::string& message) const {
    throw input_error(file_ + ": " + message);
  }

  void require_object(const json& j, const std::string& where) const {
    if (!j.is_object()) fail((where.empty() ? std::string("the spec") : where) + " must be a JSON object");
  }

  void check_keys(const json& j, const std::string& prefix,
                  std::initializer_list<std::string_view> allowed) const {
    for (auto it = j.begin(); it != j.end(); ++it) {
      bool known = false;
      for (std::string_view a : allowed) known = known || it.key() == a;
      if (!known) {
        std::string list;
        for (std::string_view a : allowed) list += (list.empty() ? "" : ", ") + std::string(a);
        fail(fmt::format("unknown key {}{} (allowed: {})", prefix, it.key(), list));
      }
    }
  }

  const json& member(const json& j, const std::string& prefix, const char* key) const {
    if (!j.contains(key)) fail(fmt::format("{}{} is required", prefix, key));
    const json& v = j[key];
    if (std::string_view(key) == "material" || std::string_view(key) == "path")
      require_object(v, prefix + key);
    return v;
  }

  double number(const json& j, const std::string& prefix, const char* key) const {
    const json& v = j[key];
    if (!v.is_number() || !std::isfinite(v.get<double>()))
      fail(fmt::format("{}{} must be a finite number", prefix, key));
    return v.get<double>();
  }

  double required_number(const json& j, const std::string& prefix, const char* key) const {
    member(j, prefix, key);
    return number(j, prefix, key);
  }

  double optional_number(const json& j, const std::string& prefix, const char* key,
                         double fallback) const {
    return j.contains(key) ? number(j, prefix, key) : fallback;
  }

 public:
  /// "model" of the spec's material: drucker_prager (default) or mu_i.
  bool is_mu_i(const json& root) const {
    if (!root.is_object() || !root.contains("material") || !root["material"].is_object()) return false;
    const json& m = root["material"];
    if (!m.contains("model")) return false;
    const json& model = m["model"];
    const std::string name = model.is_string() ? model.get<std::string>() : std::string();
    if (name != "drucker_prager" && name != "mu_i") fail("material.model must be one of drucker_prager, mu_i");
    return name == "mu_i";
  }

  // μ(I): material keys as in a scene (docs/mu-i.md), path {"type": "mu_i_shear", "pressure",
  // "inertial_number": {"min", "max", "count"} (log-spaced), "strain_increment", "increments"}.
  MuIShearSpec read_mu_i(const json& root) const {
    require_object(root, "");
    check_keys(root, "", {"description", "material", "path"});
    if (root.contains("description") && !root["description"].is_string())
      fail("description must be a string");
    MuIShearSpec spec;
    const json& m = member(root, "", "material");
    const std::string mp = "material.";
    check_keys(m, mp, {"model", "young", "poisson", "mu_s", "mu_2", "i0", "grain_diameter", "grain_density"});
    MuIParameters& p = spec.material;
    p.young = required_number(m, mp, "young");
    p.poisson = required_number(m, mp, "poisson");
    p.mu_s = optional_number(m, mp, "mu_s", p.mu_s);
    p.mu_2 = optional_number(m, mp, "mu_2", p.mu_2);
    p.i0 = optional_number(m, mp, "i0", p.i0);
    p.grain_diameter = optional_number(m, mp, "grain_diameter", p.grain_diameter);
    p.grain_density = optional_number(m, mp, "grain_density", p.grain_density);
    try {
      MuI check(p, mp);  // validates ranges; messages name material.<key>
    } catch (const Error& e) {
      fail(e.what());
    }
    const json& path = member(root, "", "path");
    const std::string pp = "path.";
    check_keys(path, pp, {"type", "pressure", "inertial_number", "strain_increment", "increments"});
    const json& type = member(path, pp, "type");
    if (!type.is_string() || type.get<std::string>() != "mu_i_shear")
      fail("path.type must be mu_i_shear for a mu_i material");
    spec.pressure = required_number(path, pp, "pressure");
    if (!(spec.pressure > 0.0))
      fail(fmt::format("path.pressure = {} is out of range; allowed > 0 (Pa, compression positive)", spec.pressure));
    const json& range = member(path, pp, "inertial_number");
    if (!range.is_object()) fail("path.inertial_number must be an object {min, max, count}");
    const std::string rp = "path.inertial_number.";
    check_keys(range, rp, {"min", "max", "count"});
    const double lo = required_number(range, rp, "min"), hi = required_number(range, rp, "max");
    if (!(lo > 0.0)) fail(fmt::format("path.inertial_number.min = {} is out of range; allowed > 0", lo));
    if (!(hi >= lo)) fail(fmt::format("path.inertial_number.max = {} is out of range; allowed >= min = {}", hi, lo));
    const json& count = member(range, rp, "count");
    if (!count.is_number_integer() || count.get<long long>() < 1 || count.get<long long>() > 100000)
      fail("path.inertial_number.count must be an integer in [1, 100000]");
    const int n = static_cast<int>(count.get<long long>());
    for (int k = 0; k < n; ++k)
      spec.inertial_numbers.push_back(n == 1 ? lo : lo * std::pow(hi / lo, static_cast<double>(k) / (n - 1)));
    spec.strain_increment = optional_number(path, pp, "strain_increment", spec.strain_increment);
    if (!(spec.strain_increment > 0.0 && spec.strain_increment <= 1.0))
      fail(fmt::format("path.strain_increment = {} is out of range; allowed (0, 1]", spec.strain_increment));
    if (path.contains("increments")) {
      const json& inc = path["increments"];
      if (!inc.is_number_integer() || inc.get<long long>() < 1 || inc.get<long long>() > 10000000)
        fail("path.increments must be an integer in [1, 10000000]");
      spec.increments = static_cast<int>(inc.get<long long>());
    }
    return spec;
  }

 private:
  DruckerPragerParameters material(const json& m) const {
    const std::string prefix = "material.";
    check_keys(m, prefix,
               {"model", "young", "poisson", "friction_angle", "dilatancy_angle", "cohesion",
                "hardening_modulus", "kinematic_fraction", "tension_cutoff", "cone"});
    DruckerPragerParameters p;
    p.young = required_number(m, prefix, "young");
    p.poisson = required_number(m, prefix, "poisson");
    p.friction_angle_deg = required_number(m, prefix, "friction_angle");
    p.dilatancy_angle_deg = optional_number(m, prefix, "dilatancy_angle", 0.0);
    p.cohesion = optional_number(m, prefix, "cohesion", 0.0);
    p.hardening_modulus = optional_number(m, prefix, "hardening_modulus", 0.0);
    p.kinematic_fraction = optional_number(m, prefix, "kinematic_fraction", 0.0);
    if (m.contains("tension_cutoff")) {
      const json& t = m["tension_cutoff"];
      if (t.is_string()) {
        if (t.get<std::string>() != "apex")
          fail("material.tension_cutoff must be \"apex\" or a mean stress >= 0 (Pa)");
      } else {
        p.tension_cutoff = number(m, prefix, "tension_cutoff");
      }
    }
    if (m.contains("cone")) {
      const json& c = m["cone"];
      const std::string name = c.is_string() ? c.get<std::string>() : std::string();
      if (name == "plane_strain") p.cone = ConeFit::PlaneStrain;
      else if (name == "compression") p.cone = ConeFit::Compression;
      else if (name == "extension") p.cone = ConeFit::Extension;
      else if (name == "inscribed") p.cone = ConeFit::Inscribed;
      else fail("material.cone must be one of plane_strain, compression, extension, inscribed");
    }
    try {
      DruckerPrager check(p, prefix);  // validates ranges; messages name material.<key>
    } catch (const Error& e) {
      fail(e.what());
    }
    return p;
  }

  void read_path(const json& path, ElementTestSpec& spec) const {
    const std::string prefix = "path.";
    const json& type_json = member(path, prefix, "type");
    const std::string type = type_json.is_string() ? type_json.get<std::string>() : std::string();
    const char* pressure_key = nullptr;
    bool pressure_required = false;
    double pressure_min_exclusive = -1.0;  // pressure must be > this
    if (type == "uniaxial_compression") {
      spec.path = ElementPath::UniaxialCompression;
      check_keys(path, prefix, {"type", "strain", "increments"});
    } else if (type == "drained_triaxial") {
      spec.path = ElementPath::DrainedTriaxial;
      pressure_key = "confining_pressure";
      pressure_required = true;
      pressure_min_exclusive = 0.0;
      check_keys(path, prefix, {"type", "strain", "increments", "confining_pressure"});
    } else if (type == "simple_shear") {
      spec.path = ElementPath::SimpleShear;
      pressure_key = "normal_stress";
      pressure_required = true;
      check_keys(path, prefix, {"type", "strain", "increments", "normal_stress", "spin"});
    } else if (type == "oedometer") {
      spec.path = ElementPath::Oedometer;
      pressure_key = "initial_pressure";
      check_keys(path, prefix, {"type", "strain", "increments", "initial_pressure"});
    } else {
      fail("path.type must be one of uniaxial_compression, simple_shear, drained_triaxial, oedometer");
    }

    if (pressure_key != nullptr) {
      spec.pressure = pressure_required ? required_number(path, prefix, pressure_key)
                                        : optional_number(path, prefix, pressure_key, 0.0);
      if (!(spec.pressure > pressure_min_exclusive))
        fail(fmt::format("{}{} = {} is out of range; allowed {} (Pa, compression positive)", prefix,
                         pressure_key, spec.pressure, pressure_min_exclusive < 0.0 ? ">= 0" : "> 0"));
    }

    // strain: one target or a list of targets, each in [-1, 1], not all zero.
    const json& strain = member(path, prefix, "strain");
    if (strain.is_number()) {
      spec.strain_targets = {number(path, prefix, "strain")};
    } else if (strain.is_array() && !strain.empty()) {
      for (std::size_t i = 0; i < strain.size(); ++i) {
        if (!strain[i].is_number() || !std::isfinite(strain[i].get<double>()))
          fail(fmt::format("path.strain[{}] must be a finite number", i));
        spec.strain_targets.push_back(strain[i].get<double>());
      }
    } else {
      fail("path.strain must be a number or a non-empty array of numbers");
    }
    bool moves = false;
    for (std::size_t i = 0; i < spec.strain_targets.size(); ++i) {
      const double s = spec.strain_targets[i];
      if (!(std::abs(s) <= 1.0))
        fail(fmt::format("path.strain{} = {} is out of range; allowed [-1, 1]",
                         strain.is_array() ? fmt::format("[{}]", i) : std::string(), s));
      moves = moves || s != 0.0;
    }
    if (!moves) fail("path.strain must contain a non-zero target");

    const json& inc = member(path, prefix, "increments");
    if (!inc.is_number_integer()) fail("path.increments must be an integer");
    const long long n = inc.get<long long>();
    if (n < 1 || n > 10000000)
      fail(fmt::format("path.increments = {} is out of range; allowed integer in [1, 10000000]", n));
    spec.increments = static_cast<int>(n);

    if (path.contains("spin")) {
      if (!path["spin"].is_boolean()) fail("path.spin must be true or false");
      spec.spin = path["spin"].get<bool>();
    }
  }
};

void run_element_test_command(const std::string& spec_file, const std::string& out_file) {
  std::ifstream in(spec_file);
  if (!in) throw io_error(fmt::format("cannot read spec file {}", spec_file));
  json root;
  try {
    root = json::parse(in);
  } catch (const json::parse_error& e) {
    throw input_error(fmt::format("{}: invalid JSON: {}", spec_file, e.what()));
  }
  const SpecReader reader(spec_file);
  if (reader.is_mu_i(root)) {
    const std::vector<MuIShearPoint> points = run_mu_i_shear_test(reader.read_mu_i(root));
    std::ofstream out(out_file);
    if (!out) throw io_error(fmt::format("cannot write {}", out_file));
    write_mu_i_shear_csv(out, points);
    out.close();
    if (!out) throw io_error(fmt::format("error while writing {}", out_file));
    double worst = 0.0;
    for (const MuIShearPoint& p : points) worst = std::fmax(worst, std::abs(p.relative_error));
    fmt::print("element-test: mu(I) simple shear at {} inertial numbers, largest |tau/p / mu(I) - 1| = {:.2e}, wrote {}\n",
               points.size(), worst, out_file);
    return;
  }
  const ElementTestSpec spec = reader.read(root);
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
      "oedometer) or mu(I) steady simple shear from a JSON spec; writes a CSV. See "
      "docs/drucker-prager.md, docs/mu-i.md.");
  auto spec_file = std::make_shared<std::string>();
  auto out_file = std::make_shared<std::string>();
  cmd->add_option("spec", *spec_file, "JSON spec (material + path), e.g. inputs/element_tests/*.json")
      ->required();
  cmd->add_option("--out,-o", *out_file, "CSV file to write")->required();
  cmd->callback([spec_file, out_file] { run_element_test_command(*spec_file, *out_file); });
}

}  // namespace talus::app
