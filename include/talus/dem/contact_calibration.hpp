#pragma once
// Contact spring constants kN, kT that make a DEM assembly behave, on average, like an isotropic
// elastic continuum with shear modulus G and Poisson's ratio nu (Abe 1996: K. Abe, JSCE 1996), and
// the inverse map (springs -> G, nu) used to check round trips. Derivations and limits: docs/dem.md.
//
// Units: in 2D the springs are per unit depth (N/m per m = Pa), as in Abe 1996, §2(1); in 3D they are
// forces per length (N/m).
//
// Refusals throw talus::input_error whose one-line message names the `talus dem-springs` option
// (--nu, ...) and the representable range, because that command is where users meet them.
#include "talus/dem/packing.hpp"

namespace talus::dem {

/// Normal and tangential stiffness of one contact (Abe 1996, eq. 1-3).
struct ContactSprings {
  double normal = 0.0;      // kN
  double tangential = 0.0;  // kT
  double tangential_to_normal() const { return tangential / normal; }
};

/// The target continuum. In 2D it is read in plane strain unless PlaneCondition::stress is asked for.
struct IsotropicElasticity {
  double shear_modulus = 0.0;  // G
  double poisson_ratio = 0.0;  // nu

  static IsotropicElasticity from_young(double young, double poisson) {
    return {young / (2.0 * (1.0 + poisson)), poisson};
  }
  double young_modulus() const { return 2.0 * shear_modulus * (1.0 + poisson_ratio); }
};

/// 2D only: Abe 1996 works in plane strain; plane stress follows by reading nu as nu/(1+nu)
/// (Abe 1996, §2(1)).
enum class PlaneCondition { strain, stress };

/// The largest Poisson's ratio the packing can represent with kT >= 0 (the limit of stable dynamic
/// DEM, Abe 1996, eq. 22 and §5(c)); for the square lattice the only representable value, 0.
double poisson_ratio_limit(Packing packing, PlaneCondition plane = PlaneCondition::strain);

/// kN, kT for the target continuum; throws talus::input_error where the packing cannot represent it.
ContactSprings calibrate_contact_springs(const IsotropicElasticity& target, const PackingGeometry& geometry,
                                         PlaneCondition plane = PlaneCondition::strain);

/// The continuum that given springs represent (inverse of calibrate_contact_springs). Throws
/// talus::input_error for a square lattice with kN != kT, which is not isotropic (Abe 1996, eq. 29).
IsotropicElasticity macroscopic_elasticity(const ContactSprings& springs, const PackingGeometry& geometry,
                                           PlaneCondition plane = PlaneCondition::strain);

}  // namespace talus::dem
