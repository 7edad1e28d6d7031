#pragma once
// The isotropic elastic constants from Young's modulus E and Poisson's ratio nu, in one place:
// shear modulus G, bulk modulus K, Lame's first parameter lambda and the P-wave modulus M.
//
// Lambda has two formulas here, equal in exact arithmetic but not always in the last bit (E = 1e7 Pa,
// nu = 0.3: they differ by 9.3e-10 Pa), and each caller keeps the one its results were computed
// with, since a refactor must not change a result by a bit:
//   lame()            E nu / ((1 + nu)(1 - 2 nu))   LinearElastic, the element test's held strains
//   lame_from_bulk()  K - 2G/3                      DruckerPrager, MuI
// (LinearElastic::bulk() is lambda + 2G/3 from its stored lambda and G: a third rounding of K, which
// its energy density and the separation rule's released energy use.)
namespace talus {

struct ElasticModuli {
  double young = 0.0;    // E [Pa]
  double poisson = 0.0;  // nu [-]

  /// G = E / (2 (1 + nu))
  double shear() const { return young / (2.0 * (1.0 + poisson)); }
  /// K = E / (3 (1 - 2 nu))
  double bulk() const { return young / (3.0 * (1.0 - 2.0 * poisson)); }
  /// lambda = E nu / ((1 + nu)(1 - 2 nu))
  double lame() const { return young * poisson / ((1.0 + poisson) * (1.0 - 2.0 * poisson)); }
  /// lambda = K - 2G/3, with bulk() and shear()
  double lame_from_bulk() const { return bulk() - 2.0 * shear() / 3.0; }
  /// The P-wave (constrained) modulus M = K + 4G/3, which sets the wave speed c = sqrt(M / rho).
  double p_wave() const { return bulk() + 4.0 / 3.0 * shear(); }
};

}  // namespace talus
