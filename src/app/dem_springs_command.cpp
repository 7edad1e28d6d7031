// `talus dem-springs`: DEM contact spring constants kN, kT from continuum constants (Abe 1996;
// docs/dem.md). Prints one JSON object; a continuum the packing cannot represent is refused with
// exit code 2 and one line, never answered with a negative spring.
#include "commands.hpp"
#include "option_checks.hpp"
#include "talus/core/error.hpp"
#include "talus/dem/contact_calibration.hpp"
#include "talus/dem/number_text.hpp"
#include "talus/dem/packing.hpp"

#include <fmt/core.h>
#include <nlohmann/json.hpp>

#include <cmath>
#include <memory>
#include <optional>
#include <string>

namespace talus::app {
namespace {

struct DemSpringsOptions {
  std::optional<double> young;
  std::optional<double> shear;
  double poisson = 0.0;
  std::string packing;
  bool plane_stress = false;
  dem::PackingParameters parameters;
};

/// The inputs are finite, but a double may not hold what follows from them (--E 1e300 with --radius
/// 1e10 gives kN = inf; --E 1e-320 a subnormal kN that has lost its digits, kT/kN 0.19975 for 0.2):
/// refuse, naming the inputs, rather than print null or a wrong ratio.
void refuse_unrepresentable(const nlohmann::ordered_json& out, const DemSpringsOptions& options) {
  for (const auto& [key, value] : out.items()) {
    if (!value.is_number_float()) continue;
    const int kind = std::fpclassify(value.get<double>());
    if (kind == FP_NORMAL || kind == FP_ZERO) continue;
    std::string inputs;
    auto add = [&inputs](const char* option, const std::optional<double>& v) {
      if (v) inputs += fmt::format("{}{} = {}", inputs.empty() ? "" : " and ", option, dem::number_text(*v));
    };
    add("--E", options.young);
    add("--G", options.shear);
    add("--density-ratio", options.parameters.density_ratio);
    add("--coordination", options.parameters.coordination);
    add("--radius", options.parameters.radius);
    const double bad = value.get<double>();
    throw input_error(fmt::format("{} = {}: the springs of {} are beyond the range of a double (about 1e-308 to 1.8e308)",
                                  key, std::isnan(bad) ? "nan" : dem::number_text(bad), inputs));
  }
}

nlohmann::ordered_json compute_dem_springs(const DemSpringsOptions& options) {
  const dem::Packing packing = dem::parse_packing(options.packing);
  if (!options.young && !options.shear) throw input_error("give exactly one of --E and --G");
  if (options.young && (!std::isfinite(*options.young) || *options.young <= 0.0)) {
    throw input_error(fmt::format("--E = {} must be a finite number > 0", *options.young));
  }
  if (options.shear && (!std::isfinite(*options.shear) || *options.shear <= 0.0)) {
    throw input_error(fmt::format("--G = {} must be a finite number > 0", *options.shear));
  }
  if (options.plane_stress && dem::is_three_dimensional(packing)) {
    throw input_error(fmt::format("--plane-stress does not apply to packing '{}', which is 3D",
                                  dem::packing_name(packing)));
  }
  const dem::PackingGeometry geometry = dem::make_packing_geometry(packing, options.parameters);
  const dem::PlaneCondition plane = options.plane_stress ? dem::PlaneCondition::stress : dem::PlaneCondition::strain;
  // E and nu are those of the material; plane stress changes only how nu enters (Abe 1996, §2(1)).
  const dem::IsotropicElasticity target =
      options.young ? dem::IsotropicElasticity::from_young(*options.young, options.poisson)
                    : dem::IsotropicElasticity{*options.shear, options.poisson};
  const dem::ContactSprings springs = dem::calibrate_contact_springs(target, geometry, plane);

  nlohmann::ordered_json out;  // keeps kN, kT first
  out["kN"] = springs.normal;
  out["kT"] = springs.tangential;
  out["kT_over_kN"] = springs.tangential_to_normal();
  out["units"] = dem::is_three_dimensional(packing) ? "N/m" : "N/m per m of depth (= Pa)";
  out["packing"] = dem::packing_name(packing);
  out["E"] = target.young_modulus();
  out["G"] = target.shear_modulus;
  out["nu"] = target.poisson_ratio;
  out["nu_limit"] = dem::poisson_ratio_limit(packing, plane);
  if (!dem::is_three_dimensional(packing)) out["plane"] = options.plane_stress ? "stress" : "strain";
  out["density_ratio"] = geometry.density_ratio;
  out["coordination"] = geometry.coordination;
  if (dem::is_three_dimensional(packing)) out["radius"] = geometry.radius;
  refuse_unrepresentable(out, options);
  return out;
}

}  // namespace

void add_dem_springs_command(CLI::App& app) {
  auto options = std::make_shared<DemSpringsOptions>();
  CLI::App* command = app.add_subcommand(
      "dem-springs",
      "DEM contact springs kN, kT that reproduce an isotropic elastic continuum (Abe 1996).\n"
      "Prints one JSON object with kN and kT (2D: per unit depth, N/m/m = Pa; 3D: N/m).\n"
      "Packings:\n"
      "  hex         2D hexagonal close packing, eq. 34 (plane strain; nu <= 1/4)\n"
      "  hex-locked  the same with disc rotations suppressed, eq. 53; matches the continuum's equilibrium\n"
      "              equation, but under boundary tractions the lattice responds with nu = (1 - kT/kN)/4\n"
      "              (docs/dem.md)\n"
      "  square      2D square lattice, eq. 30-31: only nu = 0, kN = kT = E\n"
      "  random2d    isotropic random disc packing, eq. 21 with psi = Z/(2 pi)\n"
      "              (defaults: --density-ratio 0.84, --coordination 4)\n"
      "  random3d    isotropic random sphere packing, uniform-strain (Voigt) estimate\n"
      "              nu = (1 - kT/kN)/(4 + kT/kN); needs --radius\n"
      "              (defaults: --density-ratio 0.64, --coordination 6)\n"
      "Poisson's ratios above the packing's limit need kT < 0 (unstable in dynamic DEM) and are refused\n"
      "with exit code 2. Details, derivations and verification: docs/dem.md.");
  check_number(command->add_option("--E", options->young, "Young's modulus E in Pa (give this or --G)"));
  check_number(command->add_option("--G", options->shear, "shear modulus G in Pa (give this or --E)"))
      ->excludes("--E");
  check_number(command->add_option("--nu", options->poisson, "Poisson's ratio of the material"))->required();
  command->add_option("--packing", options->packing, "hex | hex-locked | square | random2d | random3d")
      ->required();
  command->add_flag("--plane-stress", options->plane_stress,
                    "2D only: represent a plane-stress continuum (nu is read as nu/(1+nu); nu <= 1/3)");
  check_number(command->add_option("--density-ratio", options->parameters.density_ratio,
                                   "random packings: solid fraction gamma/rho (bulk over particle density), 0 < value < 1"));
  check_number(command->add_option("--coordination", options->parameters.coordination,
                                   "random packings: mean number of contacts per particle Z"));
  check_number(command->add_option("--radius", options->parameters.radius,
                                   "random3d: particle radius a in m (3D springs scale with a)"));
  command->callback([options] { fmt::print("{}\n", compute_dem_springs(*options).dump(2)); });
}

}  // namespace talus::app
