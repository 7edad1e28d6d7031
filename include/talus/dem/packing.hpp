#pragma once
// How the discs (2D) or spheres (3D) of a DEM assembly are arranged. The spring constants that make
// an assembly behave like a given continuum depend on the arrangement only through its solid fraction
// gamma/rho and its contact density (Abe 1996, eq. 11, 21), plus, in 3D, the particle radius, because
// a 3D spring constant is a force per length while a 2D one is per unit depth as well.
#include <numbers>
#include <optional>
#include <string>
#include <string_view>

namespace talus::dem {

enum class Packing {
  hexagonal,                 // 2D close packing, 6 contacts per disc (Abe 1996, eq. 32-34)
  hexagonal_rotation_locked,  // the same, disc rotations suppressed (Abe 1996, eq. 53)
  square,                    // 2D square lattice, 4 contacts per disc (Abe 1996, eq. 23-31)
  random_2d,                 // isotropic random disc packing (Abe 1996, eq. 11, 20-22)
  random_3d,                 // isotropic random sphere packing, uniform-strain hypothesis (docs/dem.md)
};

/// The spelling used by `talus dem-springs --packing`.
std::string_view packing_name(Packing packing);
/// Inverse of packing_name; throws talus::input_error naming the allowed values.
Packing parse_packing(std::string_view name);

bool is_three_dimensional(Packing packing);
bool is_regular_lattice(Packing packing);

// Solid fractions gamma/rho fixed by the lattice geometry.
inline constexpr double kHexagonalDensityRatio = std::numbers::pi / (2.0 * std::numbers::sqrt3);  // Abe 1996, §2(3)
inline constexpr double kSquareDensityRatio = std::numbers::pi / 4.0;  // Abe 1996, eq. 31: rho/gamma = 4/pi

// Defaults for random packings: the jamming point of frictionless random packings
// (O'Hern et al., Phys. Rev. E 68, 011306, 2003): solid fraction 0.84 with Z = 4 contacts per disc in
// 2D (bidisperse discs; monodisperse discs crystallise), 0.64 with Z = 6 in 3D. These are the densest
// random packings a DEM generator typically produces; docs/dem.md explains why a user should pass the
// values measured on the actual assembly instead.
inline constexpr double kDefaultRandom2dDensityRatio = 0.84;
inline constexpr double kDefaultRandom2dCoordination = 4.0;
inline constexpr double kDefaultRandom3dDensityRatio = 0.64;
inline constexpr double kDefaultRandom3dCoordination = 6.0;

/// A packing with the numbers the calibration needs; build it with make_packing_geometry, which fills
/// lattice values and defaults and rejects parameters that do not apply to the packing.
struct PackingGeometry {
  Packing packing = Packing::hexagonal;
  double density_ratio = kHexagonalDensityRatio;  // gamma/rho: bulk density over particle density
  double coordination = 6.0;                      // mean number of contacts per particle, Z
  double radius = 0.0;                            // particle radius (3D only; 0 in 2D)
};

/// Optional user-supplied parameters, as given on the command line.
struct PackingParameters {
  std::optional<double> density_ratio;  // --density-ratio: random packings only
  std::optional<double> coordination;   // --coordination: random packings only
  std::optional<double> radius;         // --radius: required for random_3d, refused in 2D
};

/// Validates the parameters for this packing (ranges, and which ones apply) and fills the rest.
/// Throws talus::input_error with a one-line message naming the `talus dem-springs` option.
PackingGeometry make_packing_geometry(Packing packing, const PackingParameters& parameters = {});

}  // namespace talus::dem
