#include "talus/dem/contact_calibration.hpp"

#include "talus/core/error.hpp"
#include "talus/dem/number_text.hpp"

#include <cmath>
#include <numbers>
#include <string>

namespace talus::dem {
namespace {

constexpr double kPi = std::numbers::pi;

// Abe 1996 derives everything in plane strain; plane stress is the same algebra with nu read as
// nu/(1+nu) (Abe 1996, §2(1)). The inverse maps the plane-strain value back.
double plane_strain_equivalent(double poisson, PlaneCondition plane) {
  return plane == PlaneCondition::stress ? poisson / (1.0 + poisson) : poisson;
}
double from_plane_strain_equivalent(double poisson, PlaneCondition plane) {
  return plane == PlaneCondition::stress ? poisson / (1.0 - poisson) : poisson;
}

std::string plane_suffix(Packing packing, PlaneCondition plane) {
  return (!is_three_dimensional(packing) && plane == PlaneCondition::stress) ? " in plane stress" : "";
}

void check_target(const IsotropicElasticity& target, const PackingGeometry& geometry, PlaneCondition plane) {
  const double g = target.shear_modulus;
  const double nu = target.poisson_ratio;
  // An isotropic solid is stable only for -1 < nu < 1/2 (positive G and bulk modulus). Checked before
  // G, which comes from nu when --E is given (nu = nan or -1 would be reported as G = nan or inf).
  if (!std::isfinite(nu) || nu <= -1.0 || nu >= 0.5) {
    throw input_error("--nu = " + number_text(nu) + " is outside (-1, 0.5), the range of a stable isotropic solid");
  }
  if (!std::isfinite(g) || g <= 0.0) {
    throw input_error("the shear modulus G = " + number_text(g) + " must be a finite number > 0 (from --E or --G)");
  }
  if (is_three_dimensional(geometry.packing) && plane == PlaneCondition::stress) {
    throw input_error("--plane-stress does not apply to packing '" + std::string(packing_name(geometry.packing)) +
                      "', which is 3D");
  }
  if (geometry.packing == Packing::square) {
    if (nu != 0.0) {
      throw input_error("--nu = " + number_text(nu) +
                        " cannot be represented by packing 'square': a square lattice gives only nu = 0 "
                        "(Abe 1996, eq. 29-31); use hex or random2d");
    }
    return;
  }
  const double limit = poisson_ratio_limit(geometry.packing, plane);
  if (nu > limit) {
    throw input_error("--nu = " + number_text(nu) + " is above the limit " + number_text_6(limit) +
                      " that packing '" + std::string(packing_name(geometry.packing)) + "' can represent" +
                      plane_suffix(geometry.packing, plane) + " (needs kT >= 0)");
  }
}

// nu is the plane-strain value in 2D.
ContactSprings springs_for(double g, double nu, const PackingGeometry& geometry) {
  switch (geometry.packing) {
    case Packing::hexagonal: {
      // Abe 1996, eq. 34
      const double scale = 2.0 / std::numbers::sqrt3 * g / (1.0 - 2.0 * nu);
      return {scale, scale * (1.0 - 4.0 * nu)};
    }
    case Packing::hexagonal_rotation_locked: {
      // Abe 1996, eq. 53
      const double scale = std::numbers::sqrt3 * g / (6.0 * (1.0 - 2.0 * nu));
      return {scale * (5.0 - 4.0 * nu), scale * (1.0 - 4.0 * nu)};
    }
    case Packing::square: {
      // Abe 1996, eq. 30 with the lattice's gamma/rho = pi/4 (eq. 31): kN = kT = E, nu = 0 so E = 2G.
      const double k = kPi / (4.0 * geometry.density_ratio) * 2.0 * g;
      return {k, k};
    }
    case Packing::random_2d: {
      // Abe 1996, eq. 21 with a uniform contact density psi = Z/(2 pi) contacts per radian.
      const double psi = geometry.coordination / (2.0 * kPi);
      const double scale = g / geometry.density_ratio / (1.0 - 2.0 * nu) / psi;
      return {scale, scale * (1.0 - 4.0 * nu)};
    }
    case Packing::random_3d: {
      // Uniform-strain (Voigt) estimate, derived in docs/dem.md:
      //   E = phi Z kN (2 kN + 3 kT) / (2 pi a (4 kN + kT)),  nu = (kN - kT)/(4 kN + kT),
      // inverted: kN = 4 pi a G (1 + nu) / (phi Z (1 - 2 nu)), kT = 4 pi a G (1 - 4 nu) / (phi Z (1 - 2 nu)).
      const double scale = 4.0 * kPi * geometry.radius * g /
                           (geometry.density_ratio * geometry.coordination * (1.0 - 2.0 * nu));
      return {scale * (1.0 + nu), scale * (1.0 - 4.0 * nu)};
    }
  }
  throw input_error("unknown packing");
}

}  // namespace

double poisson_ratio_limit(Packing packing, PlaneCondition plane) {
  if (packing == Packing::square) return 0.0;
  // kT >= 0 <=> 1 - 4 nu >= 0 in every formula below (plane-strain nu in 2D), i.e. nu <= 1/4;
  // in plane stress nu/(1+nu) <= 1/4 <=> nu <= 1/3.
  if (!is_three_dimensional(packing) && plane == PlaneCondition::stress) return 1.0 / 3.0;
  return 0.25;
}

ContactSprings calibrate_contact_springs(const IsotropicElasticity& target, const PackingGeometry& geometry,
                                         PlaneCondition plane) {
  check_target(target, geometry, plane);
  ContactSprings springs =
      springs_for(target.shear_modulus, plane_strain_equivalent(target.poisson_ratio, plane), geometry);
  // check_target admitted nu only up to the limit, so a negative kT here is rounding at the limit
  // itself (e.g. nu = 1/3 in plane stress): it stands for kT = 0.
  if (springs.tangential < 0.0) springs.tangential = 0.0;
  return springs;
}

IsotropicElasticity macroscopic_elasticity(const ContactSprings& springs, const PackingGeometry& geometry,
                                           PlaneCondition plane) {
  const double kn = springs.normal;
  const double kt = springs.tangential;
  double g = 0.0;
  double nu = 0.0;  // plane-strain value in 2D
  switch (geometry.packing) {
    case Packing::hexagonal:
    case Packing::random_2d: {
      // Abe 1996, eq. 18 vs 19: G = (gamma / 2 rho)(kN + kT) psi with psi = Z/(2 pi), i.e.
      // G = phi Z (kN + kT) / (4 pi) (= sqrt3/4 (kN + kT) for the hexagonal lattice, eq. 33); nu from eq. 22.
      g = geometry.density_ratio * geometry.coordination * (kn + kt) / (4.0 * kPi);
      nu = 0.25 * (1.0 - kt / kn);
      break;
    }
    case Packing::hexagonal_rotation_locked: {
      // Matching the locked lattice's equilibrium equation to eq. 19 (docs/dem.md):
      // G = sqrt3/4 (kN + 3 kT), G/(1 - 2 nu) = sqrt3/2 (kN - kT).
      g = std::numbers::sqrt3 / 4.0 * (kn + 3.0 * kt);
      nu = (kn - 5.0 * kt) / (4.0 * (kn - kt));
      break;
    }
    case Packing::square: {
      // Abe 1996, eq. 29: isotropic only when kN = kT; then E = (4 gamma / (pi rho)) kN and nu = 0.
      if (std::abs(kn - kt) > 1e-12 * std::abs(kn)) {
        throw input_error("a square lattice with kN = " + number_text(kn) + " != kT = " + number_text(kt) +
                          " is not isotropic (Abe 1996, eq. 29)");
      }
      g = 0.5 * 4.0 * geometry.density_ratio / kPi * kn;
      nu = 0.0;
      break;
    }
    case Packing::random_3d: {
      // Uniform-strain estimate (docs/dem.md): mu = phi Z (2 kN + 3 kT) / (20 pi a).
      g = geometry.density_ratio * geometry.coordination * (2.0 * kn + 3.0 * kt) / (20.0 * kPi * geometry.radius);
      nu = (kn - kt) / (4.0 * kn + kt);
      return {g, nu};
    }
  }
  return {g, from_plane_strain_equivalent(nu, plane)};
}

}  // namespace talus::dem
