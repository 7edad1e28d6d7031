#include "talus/dem/packing.hpp"

#include "talus/core/error.hpp"
#include "talus/dem/number_text.hpp"

#include <array>
#include <cmath>
#include <string>
#include <utility>

namespace talus::dem {
namespace {

constexpr std::array<std::pair<Packing, std::string_view>, 5> kNames{{
    {Packing::hexagonal, "hex"},
    {Packing::hexagonal_rotation_locked, "hex-locked"},
    {Packing::square, "square"},
    {Packing::random_2d, "random2d"},
    {Packing::random_3d, "random3d"},
}};

void refuse_for_lattice(Packing packing, const std::optional<double>& value, std::string_view option,
                        std::string_view what_is_fixed) {
  if (value) {
    throw input_error(std::string(option) + " does not apply to packing '" + std::string(packing_name(packing)) +
                      "': its " + std::string(what_is_fixed) + " is fixed by the lattice");
  }
}

double positive_finite(const std::optional<double>& value, double fallback, std::string_view option) {
  if (!value) return fallback;
  if (!std::isfinite(*value) || *value <= 0.0) {
    throw input_error(std::string(option) + " = " + number_text(*value) + " must be a finite number > 0");
  }
  return *value;
}

}  // namespace

std::string_view packing_name(Packing packing) {
  for (const auto& [value, name] : kNames) {
    if (value == packing) return name;
  }
  return "unknown";
}

Packing parse_packing(std::string_view name) {
  for (const auto& [value, spelling] : kNames) {
    if (spelling == name) return value;
  }
  throw input_error("--packing = '" + std::string(name) +
                    "' is not one of hex, hex-locked, square, random2d, random3d");
}

bool is_three_dimensional(Packing packing) { return packing == Packing::random_3d; }

bool is_regular_lattice(Packing packing) {
  return packing == Packing::hexagonal || packing == Packing::hexagonal_rotation_locked ||
         packing == Packing::square;
}

PackingGeometry make_packing_geometry(Packing packing, const PackingParameters& parameters) {
  PackingGeometry geometry;
  geometry.packing = packing;

  if (is_regular_lattice(packing)) {
    refuse_for_lattice(packing, parameters.density_ratio, "--density-ratio", "density ratio gamma/rho");
    refuse_for_lattice(packing, parameters.coordination, "--coordination", "number of contacts");
    if (packing == Packing::square) {
      geometry.density_ratio = kSquareDensityRatio;
      geometry.coordination = 4.0;
    } else {
      geometry.density_ratio = kHexagonalDensityRatio;
      geometry.coordination = 6.0;
    }
  } else {
    const bool three_d = is_three_dimensional(packing);
    geometry.density_ratio = positive_finite(
        parameters.density_ratio,
        three_d ? kDefaultRandom3dDensityRatio : kDefaultRandom2dDensityRatio, "--density-ratio");
    if (geometry.density_ratio >= 1.0) {
      throw input_error("--density-ratio = " + number_text(geometry.density_ratio) +
                        " must be below 1 (it is the solid fraction gamma/rho of the packing)");
    }
    geometry.coordination =
        parameters.coordination.value_or(three_d ? kDefaultRandom3dCoordination : kDefaultRandom2dCoordination);
    if (!std::isfinite(geometry.coordination))
      throw input_error("--coordination = " + number_text(geometry.coordination) + " must be a finite number");
    // A rigid packing of frictional grains needs at least d + 1 contacts per grain (isostatic); fewer
    // (2.5, or 1e-300, which gave kN = 5e307) describes no packing that carries a load. (0 and less
    // said "must be > 0", as if 1 would do.)
    const double fewest = three_d ? 4.0 : 3.0;
    if (!(geometry.coordination >= fewest)) {
      throw input_error("--coordination = " + number_text(geometry.coordination) + " is below " + number_text(fewest) +
                        ", the fewest contacts per grain of a rigid " + (three_d ? "3D" : "2D") +
                        " packing (d + 1, frictional and isostatic)");
    }
  }

  if (is_three_dimensional(packing)) {
    if (!parameters.radius) {
      throw input_error("--radius is required for packing '" + std::string(packing_name(packing)) +
                        "': 3D spring constants (N/m) scale with the particle radius");
    }
    geometry.radius = positive_finite(parameters.radius, 0.0, "--radius");
  } else if (parameters.radius) {
    throw input_error("--radius does not apply to packing '" + std::string(packing_name(packing)) +
                      "': 2D spring constants per unit depth do not depend on the disc radius");
  }
  return geometry;
}

}  // namespace talus::dem
