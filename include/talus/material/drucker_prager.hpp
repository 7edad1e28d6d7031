#pragma once
// Drucker–Prager elastoplasticity for granular material (Abe, Johansson & Konagai 2005, eq. 23–25), with a closed-form
// return mapping (cone, apex, tension cut-off) and linear combined isotropic/kinematic hardening
// (Prager's rule). Theory, derivation and verification: docs/drucker-prager.md.
//
// Sign convention: stress positive in tension, so compression has I1 = tr(sigma) < 0. The yield
// function is written for that sign,
//     f = alpha I1 + sqrt(J2(s - beta)) - k(eps_p)          (Abe, Johansson & Konagai 2005, eq. 23)
//     g = alpha_g I1 + sqrt(J2(s - beta))                   (Abe, Johansson & Konagai 2005, eq. 24, plastic potential)
//     d_eps^p = d_lambda dg/dsigma                          (Abe, Johansson & Konagai 2005, eq. 25, non-associated flow)
// with alpha > 0 (compression strengthens), s the stress deviator and beta the (deviatoric) back
// stress. Strain and stress are Sym6 Voigt vectors of TENSOR components (core/types.hpp).
//
// Equivalent plastic strain eps_p accumulates the equivalent plastic SHEAR strain,
//     d eps_p = sqrt(2 de^p : de^p)   (de^p the deviator of d_eps^p),
// which equals the engineering plastic shear strain gamma^p in simple shear; on the cone
// d eps_p = d_lambda exactly. The hardening modulus H is dk/d eps_p (units of stress).
//
// Use in the MPM loop (objective update, per particle):
//     rotate_objectively(stress, w_yz, w_xz, w_xy);          // below; see the note there
//     model.rotate_state(state, w_yz, w_xz, w_xy);           // back stress, the same way
//     DruckerPragerResult r = model.update(stress, state, d_eps);
// update() allocates nothing, makes no virtual call and has no loop or iteration: it is a closed
// form (one sqrt on the elastic path; one division and a few dozen flops more when plastic).
//
// Granular choices of Abe, Johansson & Konagai 2005 that the MPM loop makes (not this class):
//  - "Dilatancy 0 once flowing" (Abe, Johansson & Konagai 2005, sec. 7(2)): keep a second model,
//    `model.with_dilatancy(0.0)` (a cheap copy with psi = 0, same everything else), and use it for
//    particles flagged as flowing. Both models share DruckerPragerState, so switching is free.
//  - Separated particles (no contact, stress-free): set the stress to zero and reset the state with
//    `state.reset()` (or `state = DruckerPragerState{}`); nothing else is kept anywhere.
#include "talus/core/tensor.hpp"
#include "talus/core/types.hpp"
#include "talus/material/elastic_moduli.hpp"

#include <cmath>
#include <limits>
#include <numbers>
#include <string_view>

namespace talus {

// rotate_objectively() (the Hughes-Winget rotation used for stress and back stress) lives in
// core/tensor.hpp.

/// How the Drucker–Prager cone is matched to the Mohr–Coulomb hexagon (phi, c) and how alpha_g is
/// matched to the dilatancy angle psi (the same formula with psi in place of phi).
///  - PlaneStrain (default): equal strength to Mohr–Coulomb under plane strain with associated
///    flow, alpha = tan(phi)/sqrt(9 + 12 tan^2 phi), k = 3c/sqrt(9 + 12 tan^2 phi). Chosen because
///    Abe, Johansson & Konagai 2005 analyses plane-strain (2D) flows and its parameters (Table 2) are meant that way,
///    and because with this fit the dilatancy angle keeps its textbook meaning: in steady simple
///    shear d eps_v / d gamma = tan(psi) exactly (docs/drucker-prager.md, verified in the tests).
///  - Compression: outer cone through the compression meridian (triaxial compression exact),
///    alpha = 2 sin(phi)/(sqrt(3)(3 - sin phi)), k = 6 c cos(phi)/(sqrt(3)(3 - sin phi)).
///  - Extension: through the extension meridian (triaxial extension exact),
///    alpha = 2 sin(phi)/(sqrt(3)(3 + sin phi)), k = 6 c cos(phi)/(sqrt(3)(3 + sin phi)).
///  - Inscribed: largest cone inside the hexagon,
///    alpha = sin(phi)/sqrt(9 + 3 sin^2 phi), k = 3 c cos(phi)/sqrt(9 + 3 sin^2 phi).
enum class ConeFit { PlaneStrain, Compression, Extension, Inscribed };

/// Material constants, SI units, angles in degrees. Validated by the DruckerPrager constructor.
struct DruckerPragerParameters {
  double young = 0.0;                ///< E > 0 [Pa]
  double poisson = 0.0;              ///< nu in [0, 0.5)
  double friction_angle_deg = 0.0;   ///< phi in (0, 90) degrees
  double dilatancy_angle_deg = 0.0;  ///< psi in [0, phi] degrees; psi = phi is associated flow
  double cohesion = 0.0;             ///< c >= 0 [Pa]
  double hardening_modulus = 0.0;    ///< H = dk/d eps_p >= 0 [Pa]; 0 is perfect plasticity
  /// Prager mixing: share of H that goes to kinematic hardening, in [0, 1].
  /// 0 = purely isotropic (the cone grows: dk = H d eps_p), 1 = purely kinematic (the cone
  /// translates in the deviatoric plane: d beta = 2 H de^p), between: dk = (1 - m) H d eps_p and
  /// d beta = 2 m H de^p. Under monotonic proportional loading every m gives the same curve; they
  /// differ after a load reversal (Bauschinger effect). Abe, Johansson & Konagai 2005, Table 2 gives a "combined
  /// hardening parameter" 0.8; read as Chen & Mizuno's M (the isotropic share, seed ref. 4),
  /// that is kinematic_fraction = 1 - M = 0.2. With H = 0 (as in Table 2) it has no effect.
  double kinematic_fraction = 0.0;
  /// E and nu, for the moduli the model derives from them (elastic_moduli.hpp).
  ElasticModuli moduli() const { return {young, poisson}; }
  /// Largest admissible mean stress p = I1/3 [Pa] (tension positive), >= 0. The default, +inf,
  /// means "at the apex": the cone's apex I1 = k/alpha is the only tension limit. A finite value
  /// below the apex caps the cone with the plane I1 = 3 tension_cutoff.
  double tension_cutoff = std::numeric_limits<double>::infinity();
  ConeFit cone = ConeFit::PlaneStrain;
};

/// Plastic state of one material point. Exists only for bodies of this material.
struct DruckerPragerState {
  double equivalent_plastic_strain = 0.0;  ///< eps_p = integral of sqrt(2 de^p : de^p), >= 0
  Sym6 back_stress = Sym6::Zero();         ///< beta, deviatoric (trace zero) [Pa]
  /// Back to the virgin state (separated particles, fresh material).
  void reset() {
    equivalent_plastic_strain = 0.0;
    back_stress.setZero();
  }
};

struct DruckerPragerResult {
  /// sigma_{n+1} : d_eps^p per unit volume in this increment [J/m^3]. It is >= 0 whenever the
  /// back stress is zero (kinematic_fraction = 0 or H = 0); with kinematic hardening it can be
  /// negative after a load reversal (stored back-stress energy is released).
  double plastic_work = 0.0;
  enum class Regime { Elastic, Cone, Apex, TensionCutoff } regime = Regime::Elastic;
};

class DruckerPrager {
 public:
  /// Validates the parameters; throws talus::input_error naming `key_prefix` + the parameter
  /// ("friction_angle", "dilatancy_angle", ...) and its allowed range.
  explicit DruckerPrager(const DruckerPragerParameters& parameters,
                         std::string_view key_prefix = "");

  /// Elastic trial step sigma += lambda tr(d_eps) I + 2 G d_eps, then return mapping in closed
  /// form. `stress` must already be rotated to the end of the step (objective update, see top).
  /// After a plastic return |f| <= 1e-10 relative to the stress scale.
  /// Inline: the elastic trial and the yield test run for every particle every step; only the
  /// return mapping (plastic_return) is a call.
  DruckerPragerResult update(Sym6& stress, DruckerPragerState& state,
                             const Sym6& strain_increment) const;

  /// Rotates the back stress by the spin increment (w_yz, w_xz, w_xy) with
  /// rotate_objectively(); rotate the stress with the same function so that s - beta rotates
  /// consistently.
  void rotate_state(DruckerPragerState& state, double w_yz, double w_xz, double w_xy) const;

  /// f = alpha I1 + sqrt(J2(s - beta)) - k(eps_p)   (Abe, Johansson & Konagai 2005, eq. 23). <= 0 is admissible.
  double yield_function(const Sym6& stress, const DruckerPragerState& state) const;

  /// A copy with another dilatancy angle (degrees, validated in [0, phi]); for "psi = 0 once
  /// flowing" use with_dilatancy(0.0).
  DruckerPrager with_dilatancy(double dilatancy_angle_deg) const;

  /// Current isotropic strength k(eps_p) = k0 + (1 - m) H eps_p.
  double strength(const DruckerPragerState& state) const {
    return k0_ + hardening_isotropic_ * state.equivalent_plastic_strain;
  }
  /// Largest admissible I1 for this state: min(k/alpha, 3 tension_cutoff).
  double max_first_invariant(const DruckerPragerState& state) const;

  const DruckerPragerParameters& parameters() const { return parameters_; }
  double alpha() const { return alpha_; }          ///< friction coefficient of f
  double alpha_dilatancy() const { return alpha_g_; }  ///< alpha_g of g
  double initial_strength() const { return k0_; }  ///< k0 (from the cohesion)
  double shear_modulus() const { return shear_; }
  double bulk_modulus() const { return bulk_; }
  double lame_lambda() const { return lame_; }
  double hardening_isotropic() const { return hardening_isotropic_; }  ///< (1 - m) H
  double hardening_kinematic() const { return hardening_kinematic_; }  ///< m H
  double first_invariant_cutoff() const { return first_invariant_cutoff_; }  ///< 3 tension_cutoff (may be +inf)
  double cone_denominator() const { return cone_denominator_; }  ///< G + 9 K alpha alpha_g + H

  /// alpha and k of a cone fit for angle phi (degrees) and cohesion c: the formulas above.
  static void cone_coefficients(ConeFit cone, double angle_deg, double cohesion, double& alpha,
                                double& k);

 private:
  DruckerPragerParameters parameters_;
  double shear_ = 0.0, bulk_ = 0.0, lame_ = 0.0;
  double alpha_ = 0.0, alpha_g_ = 0.0, k0_ = 0.0;
  double hardening_isotropic_ = 0.0, hardening_kinematic_ = 0.0;
  double first_invariant_cutoff_ = 0.0;  // 3 tension_cutoff (may be +inf)
  double cone_denominator_ = 0.0;        // G + 9 K alpha alpha_g + H

  /// Steps 3-5 of update() for a trial state outside the elastic domain (f > 0 or I1 beyond the
  /// cut-off): xi = s_trial - beta, |xi|, the trial I1 and f.
  DruckerPragerResult plastic_return(Sym6& stress, DruckerPragerState& state, const Sym6& xi, double xi_norm,
                                     double i1, double f) const;
};

inline DruckerPragerResult DruckerPrager::update(Sym6& stress, DruckerPragerState& state,
                                                 const Sym6& strain_increment) const {
  // Plain arrays, element by element, copied into Sym6 only for the (rarer) plastic return: the
  // caller fills `stress` one component at a time, and Eigen two-wide loads of it, or a Sym6 that
  // escapes into the out-of-line return, kept it on the stack with stalled reloads (store
  // forwarding) that were 7% of a Drucker-Prager step.
  // The vector kernel of solver/material_kernels.cpp does steps 1-3 (trial, yield test, return to
  // the cone) lane by lane in exactly these operations; change both together (the ISA test of
  // tests/solver compares them bit for bit).
  // 1. Elastic trial: sigma += lambda tr(d_eps) I + 2 G d_eps (tensor shear components).
  const double de_v = strain_increment[XX] + strain_increment[YY] + strain_increment[ZZ];
  double trial[6];
  for (int c = 0; c < 6; ++c) trial[c] = stress[c] + 2.0 * shear_ * strain_increment[c];
  for (int c = 0; c < 3; ++c) trial[c] += lame_ * de_v;

  // 2. Trial invariants, relative to the back stress: xi = s - beta, q = sqrt(J2(xi)).
  const double i1 = trial[XX] + trial[YY] + trial[ZZ];
  const double mean = i1 / 3.0;
  double xi[6];
  for (int c = 0; c < 6; ++c) xi[c] = trial[c] - state.back_stress[c] - (c < 3 ? mean : 0.0);
  const double xi_norm = std::sqrt(xi[XX] * xi[XX] + xi[YY] * xi[YY] + xi[ZZ] * xi[ZZ] +
                                   2.0 * (xi[YZ] * xi[YZ] + xi[XZ] * xi[XZ] + xi[XY] * xi[XY]));  // sqrt(2) q
  const double q = xi_norm / std::numbers::sqrt2;
  const double k = k0_ + hardening_isotropic_ * state.equivalent_plastic_strain;
  const double f = alpha_ * i1 + q - k;  // Abe, Johansson & Konagai 2005, eq. 23 at the trial state
  if (f <= 0.0 && i1 <= first_invariant_cutoff_) {  // elastic
    for (int c = 0; c < 6; ++c) stress[c] = trial[c];
    return {};
  }
  Sym6 returned, deviator_trial;
  for (int c = 0; c < 6; ++c) {
    returned[c] = trial[c];
    deviator_trial[c] = xi[c];
  }
  const DruckerPragerResult result = plastic_return(returned, state, deviator_trial, xi_norm, i1, f);
  stress = returned;
  return result;
}

}  // namespace talus
