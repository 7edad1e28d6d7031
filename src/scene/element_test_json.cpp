// The element test's spec: {"description": ..., "material": {...}, "path": {...}} (docs/drucker-prager.md
// "Element tests"). The material is the scene's Drucker-Prager table; the path's keys depend on its type.
#include "talus/scene/element_test_json.hpp"

#include "scene_fields.hpp"

#include <cmath>

namespace talus {

namespace {

using namespace scene_detail;

struct SpecDraft {
  ElementTestSpec spec;
  std::string description;
};

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
      [](const ElementTestSpec& s, Json& j) { j["strain"] = s.strain_targets; }, {.required = true});
}

Table<ElementTestSpec> path_table() {
  using S = ElementTestSpec;
  Table<S> t;
  t.selector = "type";
  t.values = {"uniaxial_compression", "simple_shear", "drained_triaxial", "oedometer"};
  t.selected = [](const S& s) {
    switch (s.path) {
      case ElementPath::UniaxialCompression: return std::string("uniaxial_compression");
      case ElementPath::SimpleShear: return std::string("simple_shear");
      case ElementPath::DrainedTriaxial: return std::string("drained_triaxial");
      case ElementPath::Oedometer: return std::string("oedometer");
    }
    return std::string();
  };
  t.fields = {
      choice<S>("type", TALUS_AT(path),
                std::vector<std::pair<std::string, ElementPath>>{{"uniaxial_compression", ElementPath::UniaxialCompression},
                                                                 {"simple_shear", ElementPath::SimpleShear},
                                                                 {"drained_triaxial", ElementPath::DrainedTriaxial},
                                                                 {"oedometer", ElementPath::Oedometer}},
                "the loading path (material/element_test.hpp)", {.required = true}),
      number<S>("confining_pressure", TALUS_AT(pressure), {0.0, kHuge, true}, "lateral pressure, compression positive",
                {.unit = "Pa", .required = true, .when = {"drained_triaxial"}}),
      number<S>("normal_stress", TALUS_AT(pressure), {0.0, kHuge}, "constant normal stress, compression positive",
                {.unit = "Pa", .required = true, .when = {"simple_shear"}}),
      number<S>("initial_pressure", TALUS_AT(pressure), {0.0, kHuge}, "initial isotropic pressure, compression positive",
                {.unit = "Pa", .when = {"oedometer"}}),
      strain_field(),
      integer<S>("increments", TALUS_AT(increments), 1, 10000000, "increments over the whole path",
                 {.required = true}),
      boolean<S>("spin", TALUS_AT(spin), "apply the path's spin to the stress (Jaumann rate, as the MPM loop does)",
                 {.when = {"simple_shear"}}),
  };
  return t;
}

const Table<SpecDraft>& spec_table() {
  static const Table<SpecDraft> table = [] {
    Table<SpecDraft> t;
    t.fields = {
        string<SpecDraft>("description", TALUS_AT(description), "free text"),
        custom_object<SpecDraft>(
            "material", drucker_prager_table(), "required", "the Drucker-Prager constants (as a scene material's)",
            [](ObjectReader& r, SpecDraft& d) {
              ObjectReader material = r.object("material");
              read_fields(material, d.spec.material, drucker_prager_table());
            },
            [](const SpecDraft& d, Json& j) { j["material"] = write_fields(d.spec.material, drucker_prager_table()); },
            {.required = true}),
        custom_object<SpecDraft>(
            "path", path_table(), "required", "the strain or mixed path",
            [](ObjectReader& r, SpecDraft& d) {
              ObjectReader path = r.object("path");
              read_fields(path, d.spec, path_table());
            },
            [](const SpecDraft& d, Json& j) { j["path"] = write_fields(d.spec, path_table()); }, {.required = true}),
    };
    return t;
  }();
  return table;
}

}  // namespace

ElementTestSpec parse_element_test(const std::string& text, const std::string& source) {
  const Json root = parse_json(text, source);
  SpecDraft draft;
  ObjectReader r(root, "");
  read_fields(r, draft, spec_table());
  return draft.spec;
}

ElementTestSpec read_element_test_file(const std::string& path) {
  const auto text = read_text_file(path);
  if (!text) throw io_error(fmt::format("cannot read spec file {}", path));
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
