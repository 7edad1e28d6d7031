// The element test's spec: {"description": ..., "material": {...}, "path": {...}} (docs/drucker-prager.md
// "Element tests", docs/mu-i.md). The material is the scene's Drucker-Prager or μ(I) table, chosen by
// "model"; the path's keys depend on its type (mu_i_shear for a μ(I) material, the others for
// Drucker-Prager).
#include "talus/scene/element_test_json.hpp"

#include "scene_fields.hpp"

#include <cmath>

namespace talus {

namespace {

using namespace scene_detail;

struct SpecDraft {
  ElementTestRequest request;
  std::string path_type = "uniaxial_compression";
  std::string description;
};

const std::vector<std::string> kDruckerPragerPaths = {"uniaxial_compression", "simple_shear", "drained_triaxial",
                                                      "oedometer"};
const std::vector<std::string> kMuIPaths = {"mu_i_shear"};

#define TALUS_AT(member) [](auto& d) -> auto& { return d.member; }

// strain: one target or a list of targets, each in [-1, 1], not all zero.
Field<ElementTestSpec> strain_field() {
  return custom<ElementTestSpec>(
      "strain", "number or [numbers]", "required", "[-1, 1], not all 0",
      "target(s) of the control strain from 0: axial shortening (compression positive) or the shear strain γ_xy; "
      "more than one target gives unloading / reversal legs",
      {{"oneOf", Json::array({{{"type", "number"}, {"minimum", -1}, {"maximum", 1}},
                              {{"type", "array"},
                               {"minItems", 1},
                               {"items", {{"type", "number"}, {"minimum", -1}, {"maximum", 1}}}}})}},
      [](ObjectReader& r, ElementTestSpec& s) {
        const Json& strain = r.raw("strain");
        const std::string path = r.key_path("strain");
        if (strain.is_number()) {
          s.strain_targets = {ObjectReader::check_number(strain, path, -1.0, 1.0, false, false)};
        } else if (strain.is_array() && !strain.empty()) {
          for (std::size_t i = 0; i < strain.size(); ++i)
            s.strain_targets.push_back(
                ObjectReader::check_number(strain[i], fmt::format("{}[{}]", path, i), -1.0, 1.0, false, false));
        } else {
          throw input_error(fmt::format("{} must be a number or a non-empty array of numbers, got {}", path, strain.dump()));
        }
        bool moves = false;
        for (double t : s.strain_targets) moves = moves || t != 0.0;
        if (!moves) throw input_error(fmt::format("{} must contain a non-zero target", path));
      },
      [](const ElementTestSpec& s, Json& j) { j["strain"] = s.strain_targets; },
      {.required = true, .when = kDruckerPragerPaths});
}

Fields<ElementTestSpec> drucker_prager_path_fields() {
  using S = ElementTestSpec;
  return {
      number<S>("confining_pressure", TALUS_AT(pressure), {0.0, kHuge, true}, "lateral pressure, compression positive",
                {.unit = "Pa", .required = true, .when = {"drained_triaxial"}}),
      number<S>("normal_stress", TALUS_AT(pressure), {0.0, kHuge}, "constant normal stress, compression positive",
                {.unit = "Pa", .required = true, .when = {"simple_shear"}}),
      number<S>("initial_pressure", TALUS_AT(pressure), {0.0, kHuge}, "initial isotropic pressure, compression positive",
                {.unit = "Pa", .when = {"oedometer"}}),
      strain_field(),
      integer<S>("increments", TALUS_AT(increments), 1, 10000000, "increments over the whole path",
                 {.required = true, .when = kDruckerPragerPaths}),
      boolean<S>("spin", TALUS_AT(spin), "apply the path's spin to the stress (Jaumann rate, as the MPM loop does)",
                 {.when = {"simple_shear"}}),
  };
}

// μ(I) steady simple shear (docs/mu-i.md): constant pressure, imposed inertial numbers, log-spaced.
Field<MuIShearSpec> inertial_number_field() {
  Json number = {{"type", "number"}, {"exclusiveMinimum", 0}};
  return custom<MuIShearSpec>(
      "inertial_number", "object", "required", "{min > 0, max ≥ min, count in [1, 100000]; 1 only with max = min}",
      "the imposed inertial numbers I: `count` values from `min` to `max`, log-spaced",
      {{"type", "object"},
       {"properties", {{"min", number}, {"max", number}, {"count", {{"type", "integer"}, {"minimum", 1}, {"maximum", 100000}}}}},
       {"required", Json::array({"min", "max", "count"})},
       {"additionalProperties", false}},
      [](ObjectReader& r, MuIShearSpec& s) {
        ObjectReader range = r.object("inertial_number");
        const double lo = range.number("min", 0.0, kHuge, true);
        // (its lower limit is min: "max = 0.001 is outside [0.01, inf)" did not say where 0.01 came from)
        if (const Json max = range.has("max") ? range.raw("max") : Json(); max.is_number() && max.get<double>() < lo)
          throw input_error(fmt::format("{} = {} is below {} = {}: give max >= min", range.key_path("max"),
                                        max.get<double>(), range.key_path("min"), lo));
        const double hi = range.number("max", lo, kHuge);
        const int n = range.integer("count", 1, 100000);
        // (one value from a range was min, with max ignored without a word)
        if (n == 1 && hi != lo)
          throw input_error(fmt::format("{} = 1 gives one inertial number, but min = {} and max = {} differ; give max = "
                                        "min, or a count of 2 or more",
                                        range.key_path("count"), lo, hi));
        range.finish();
        s.inertial_numbers.clear();
        for (int k = 0; k < n; ++k)
          s.inertial_numbers.push_back(n == 1 ? lo : lo * std::pow(hi / lo, static_cast<double>(k) / (n - 1)));
      },
      [](const MuIShearSpec& s, Json& j) {
        if (s.inertial_numbers.empty()) return;
        j["inertial_number"] = {{"min", s.inertial_numbers.front()},
                                {"max", s.inertial_numbers.back()},
                                {"count", s.inertial_numbers.size()}};
      },
      {.required = true});
}

Fields<MuIShearSpec> mu_i_path_fields() {
  using S = MuIShearSpec;
  return {
      number<S>("pressure", TALUS_AT(pressure), {0.0, kHuge, true}, "constant pressure, compression positive",
                {.unit = "Pa", .required = true}),
      inertial_number_field(),
      number<S>("strain_increment", TALUS_AT(strain_increment), {0.0, 1.0, true, false},
                "engineering shear strain per increment, γ̇ dt"),
      integer<S>("increments", TALUS_AT(increments), 1, 10000000, "increments per inertial number"),
  };
}

Table<SpecDraft> path_table() {
  using S = SpecDraft;
  Table<S> t;
  t.selector = "type";
  t.values = kDruckerPragerPaths;
  t.values.insert(t.values.end(), kMuIPaths.begin(), kMuIPaths.end());
  t.selected = [](const S& d) { return d.path_type; };
  std::vector<std::string> words = t.values;
  t.fields = join<S>({
      {custom<S>(
          "type", "string", "required", choices_text(words),
          "the loading path (material/element_test.hpp; mu_i_shear: material/mu_i_shear_test.hpp, for a mu_i material)",
          {{"type", "string"}, {"enum", words}},
          [words](ObjectReader& r, S& d) {
            d.path_type = r.choice("type", std::string(), words);
            const std::vector<std::pair<std::string, ElementPath>> paths = {
                {"uniaxial_compression", ElementPath::UniaxialCompression},
                {"simple_shear", ElementPath::SimpleShear},
                {"drained_triaxial", ElementPath::DrainedTriaxial},
                {"oedometer", ElementPath::Oedometer}};
            for (const auto& [w, path] : paths)
              if (w == d.path_type) d.request.drucker_prager.path = path;
          },
          [](const S& d, Json& j) { j["type"] = d.path_type; }, {.required = true})},
      lift<S, ElementTestSpec>(drucker_prager_path_fields(), TALUS_AT(request.drucker_prager)),  // each names its paths
      lift<S, MuIShearSpec>(mu_i_path_fields(), TALUS_AT(request.mu_i), kMuIPaths),
  });
  return t;
}
const Table<SpecDraft>& path_fields() {
  static const Table<SpecDraft> table = path_table();
  return table;
}

// The material: the scene's Drucker-Prager fields (the default) or its μ(I) fields, by "model".
Table<SpecDraft> material_table() {
  using S = SpecDraft;
  const std::vector<std::string> dp = {"drucker_prager"}, mu_i = {"mu_i"};
  Table<S> t;
  t.selector = "model";
  t.values = {"drucker_prager", "mu_i"};
  t.selected = [](const S& d) {
    return std::string(d.request.model == ElementTestRequest::Model::MuI ? "mu_i" : "drucker_prager");
  };
  t.fields = join<S>({
      {choice<S>("model", TALUS_AT(request.model),
                 std::vector<std::pair<std::string, ElementTestRequest::Model>>{
                     {"drucker_prager", ElementTestRequest::Model::DruckerPrager}, {"mu_i", ElementTestRequest::Model::MuI}},
                 "constitutive model, as a scene material's")},
      lift<S, DruckerPragerParameters>(drucker_prager_table().fields, TALUS_AT(request.drucker_prager.material), dp),
      lift<S, MuIParameters>(mu_i_table().fields, TALUS_AT(request.mu_i.material), mu_i),
  });
  return t;
}
const Table<SpecDraft>& material_fields() {
  static const Table<SpecDraft> table = material_table();
  return table;
}

const Table<SpecDraft>& spec_table() {
  static const Table<SpecDraft> table = [] {
    Table<SpecDraft> t;
    t.fields = {
        string<SpecDraft>("description", TALUS_AT(description), "free text"),
        custom_object<SpecDraft>(
            "material", material_fields(), "required",
            "the material constants, as a scene material's (model drucker_prager or mu_i)",
            [](ObjectReader& r, SpecDraft& d) {
              ObjectReader material = r.object("material");
              read_fields(material, d, material_fields());
            },
            [](const SpecDraft& d, Json& j) { j["material"] = write_fields(d, material_fields()); }, {.required = true}),
        custom_object<SpecDraft>(
            "path", path_fields(), "required", "the strain or mixed path",
            [](ObjectReader& r, SpecDraft& d) {
              ObjectReader path = r.object("path");
              read_fields(path, d, path_fields());
              const bool mu_i = d.request.model == ElementTestRequest::Model::MuI;
              const bool mu_i_path = d.path_type == "mu_i_shear";
              if (mu_i != mu_i_path)
                throw input_error(fmt::format("{} = \"{}\" does not fit material.model = \"{}\"; allowed {}",
                                              path.key_path("type"), d.path_type, mu_i ? "mu_i" : "drucker_prager",
                                              choices_text(mu_i ? kMuIPaths : kDruckerPragerPaths)));
            },
            [](const SpecDraft& d, Json& j) { j["path"] = write_fields(d, path_fields()); }, {.required = true}),
    };
    return t;
  }();
  return table;
}

}  // namespace

ElementTestRequest parse_element_test_request(const std::string& text, const std::string& source) {
  const Json root = parse_json(text, source);
  SpecDraft draft;
  ObjectReader r(root, "");
  read_fields(r, draft, spec_table());
  return draft.request;
}

ElementTestRequest read_element_test_request(const std::string& path) {
  const auto text = read_text_file(path);
  if (!text) throw io_error(fmt::format("cannot read spec file {}{}", path, why_unreadable(path)));
  return parse_element_test_request(*text, path);
}

ElementTestSpec parse_element_test(const std::string& text, const std::string& source) {
  const ElementTestRequest request = parse_element_test_request(text, source);
  if (request.model != ElementTestRequest::Model::DruckerPrager)
    throw input_error("material.model = \"mu_i\": this reader takes a Drucker-Prager spec only");
  return request.drucker_prager;
}

ElementTestSpec read_element_test_file(const std::string& path) {
  const auto text = read_text_file(path);
  if (!text) throw io_error(fmt::format("cannot read spec file {}{}", path, why_unreadable(path)));
  return parse_element_test(*text, path);
}

nlohmann::json element_test_json_schema() {
  Json schema = {{"$schema", "http://json-schema.org/draft-07/schema#"},
                 {"title", "talus element test"},
                 {"description",
                  "A `talus element-test` spec (docs/drucker-prager.md). Made by `talus schema --element-test` from "
                  "the reader's field tables; do not edit by hand."}};
  schema.update(schema_of(spec_table()));
  return schema;
}

}  // namespace talus
