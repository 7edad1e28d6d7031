// Drucker–Prager return mapping in closed form. Derivation: docs/drucker-prager.md, sec. 4.
#include "talus/material/drucker_prager.hpp"

#include "talus/core/error.hpp"
#include "talus/core/tensor.hpp"

#include <cmath>
#include <limits>
#include <string>

namespace talus {

namespace {

constexpr double kSqrt2 = std::numbers::sqrt2;  // as in update() (drucker_prager.hpp)
constexpr double kSqrt3 = 1.7320508075688772;
constexpr double kDegree = 3.14159265358979323846 / 180.0;

void validate(const DruckerPragerParameters& p, std::string_view prefix) {
  // Written as !(inside) so that NaN is rejected too.
  if (!(p.young > 0.0 && std::isfinite(p.young)))
    throw_out_of_range(prefix, "young", p.young, "E > 0 (Pa, finite)");
  if (!(p.poisson >= 0.0 && p.poisson < 0.5))
    throw_out_of_range(prefix, "poisson", p.poisson, "[0, 0.5)");
  if (!(p.friction_angle_deg > 0.0 && p.friction_angle_deg < 90.0))
    throw_out_of_range(prefix, "friction_angle", p.friction_angle_deg, "(0, 90) degrees");
  if (!(p.dilatancy_angle_deg >= 0.0 && p.dilatancy_angle_deg <= p.friction_angle_deg))
    throw_out_of_range(prefix, "dilatancy_angle", p.dilatancy_angle_deg,
                       "[0, friction_angle] = [0, " + number_g(p.friction_angle_deg) + "] degrees");
  if (!(p.cohesion >= 0.0 && std::isfinite(p.cohesion)))
    throw_out_of_range(prefix, "cohesion", p.cohesion, "c >= 0 (Pa, finite)");
  if (!(p.hardening_modulus >= 0.0 && std::isfinite(p.hardening_modulus)))
    throw_out_of_range(prefix, "hardening_modulus", p.hardening_modulus, "H >= 0 (Pa, finite)");
  if (!(p.kinematic_fraction >= 0.0 && p.kinematic_fraction <= 1.0))
    throw_out_of_range(prefix, "kinematic_fraction", p.kinematic_fraction,
                       "[0, 1] (0 isotropic, 1 kinematic)");
  if (!(p.tension_cutoff >= 0.0))
    throw_out_of_range(prefix, "tension_cutoff", p.tension_cutoff,
                       "mean stress >= 0 (Pa), or the apex (default)");
}

}  // namespace

void DruckerPrager::cone_coefficients(ConeFit cone, double angle_deg, double cohesion,
                                      double& alpha, double& k) {
  const double a = angle_deg * kDegree;
  const double s = std::sin(a), c = std::cos(a), t = std::tan(a);
  switch (cone) {
    case ConeFit::PlaneStrain: {  // Chen & Mizuno (1990); plane strain, associated flow
      const double d = std::sqrt(9.0 + 12.0 * t * t);
      alpha = t / d;
      k = 3.0 * cohesion / d;
      return;
    }
    case ConeFit::Compression:
      alpha = 2.0 * s / (kSqrt3 * (3.0 - s));
      k = 6.0 * cohesion * c / (kSqrt3 * (3.0 - s));
      return;
    case ConeFit::Extension:
      alpha = 2.0 * s / (kSqrt3 * (3.0 + s));
      k = 6.0 * cohesion * c / (kSqrt3 * (3.0 + s));
      return;
    case ConeFit::Inscribed: {
      const double d = std::sqrt(9.0 + 3.0 * s * s);
      alpha = s / d;
      k = 3.0 * cohesion * c / d;
      return;
    }
  }
  alpha = k = 0.0;  // unreachable for a valid enum
}

DruckerPrager::DruckerPrager(const DruckerPragerParameters& parameters, std::string_view key_prefix)
    : parameters_(parameters) {
  validate(parameters_, key_prefix);
  const ElasticModuli moduli = parameters_.moduli();
  shear_ = moduli.shear();
  bulk_ = moduli.bulk();
  lame_ = moduli.lame_from_bulk();
  cone_coefficients(parameters_.cone, parameters_.friction_angle_deg, parameters_.cohesion, alpha_,
                    k0_);  // Abe, Johansson & Konagai 2005, eq. 23: alpha from phi
  double unused = 0.0;
  cone_coefficients(parameters_.cone, parameters_.dilatancy_angle_deg, 0.0, alpha_g_,
                    unused);  // Abe, Johansson & Konagai 2005, eq. 24: alpha_g from psi
  const double h = parameters_.hardening_modulus, m = parameters_.kinematic_fraction;
  hardening_isotropic_ = (1.0 - m) * h;
  hardening_kinematic_ = m * h;
  first_invariant_cutoff_ = 3.0 * parameters_.tension_cutoff;
  cone_denominator_ = shear_ + 9.0 * bulk_ * alpha_ * alpha_g_ + h;
}

DruckerPrager DruckerPrager::with_dilatancy(double dilatancy_angle_deg) const {
  DruckerPragerParameters p = parameters_;
  p.dilatancy_angle_deg = dilatancy_angle_deg;
  return DruckerPrager(p);
}

double DruckerPrager::max_first_invariant(const DruckerPragerState& state) const {
  return std::fmin(strength(state) / alpha_, first_invariant_cutoff_);
}

double DruckerPrager::yield_function(const Sym6& stress, const DruckerPragerState& state) const {
  const Sym6 xi = deviator(stress) - state.back_stress;
  return alpha_ * trace(stress) + std::sqrt(0.5 * double_contract(xi, xi)) - strength(state);
}

void DruckerPrager::rotate_state(DruckerPragerState& state, double w_yz, double w_xz,
                                 double w_xy) const {
  // The back stress is a stress-like tensor: same co-rotational (Jaumann) rate as sigma,
  // integrated by the same orthogonal rotation (stays deviatoric: the trace is invariant).
  rotate_objectively(state.back_stress, w_yz, w_xz, w_xy);
}

DruckerPragerResult DruckerPrager::plastic_return(Sym6& stress, DruckerPragerState& state, const Sym6& xi, double xi_norm,
                                                  double i1, double f) const {
  using Regime = DruckerPragerResult::Regime;
  const double g = shear_, kb = bulk_;
  const double hi = hardening_isotropic_, hk = hardening_kinematic_;
  const double q = xi_norm / kSqrt2;
  const double k = k0_ + hi * state.equivalent_plastic_strain;
  const double i1_cut = first_invariant_cutoff_;

  DruckerPragerResult result;

  // Writes sigma = xi_new + beta_new + I1/3 I for a return along n = xi/|xi| that shrinks |xi|
  // to sqrt(2) q_new with plastic multiplier dl (deviatoric plastic strain dl n/sqrt(2)), and
  // returns beta_new : n / sqrt(2) (for the plastic work).
  auto radial_return = [&](double dl, double q_new, double i1_new) {
    const double scale = q_new / q;  // q > 0 whenever this is called (q_new >= 0, dl > 0)
    const double kin = kSqrt2 * hk * dl / xi_norm;  // d beta = sqrt(2) H_kin dl n
    state.back_stress += kin * xi;
    state.equivalent_plastic_strain += dl;
    stress = scale * xi + state.back_stress;
    const double m = i1_new / 3.0;
    stress[XX] += m;
    stress[YY] += m;
    stress[ZZ] += m;
    return double_contract(state.back_stress, xi) / (kSqrt2 * xi_norm);
  };

  // 3. Return to the cone (smooth part of f): closed form because f is linear in dl along the
  //    return path: I1 = I1tr - 9 K alpha_g dl, q = qtr - (G + H_kin) dl, k = k_n + H_iso dl,
  //    so f(dl) = f_tr - (G + 9 K alpha alpha_g + H) dl = 0.
  if (f > 0.0) {
    const double dl = f / cone_denominator_;
    const double q_new = q - (g + hk) * dl;
    const double i1_new = i1 - 9.0 * kb * alpha_g_ * dl;
    if (q_new >= 0.0 && i1_new <= i1_cut) {
      result.regime = Regime::Cone;
      const double beta_n = radial_return(dl, q_new, i1_new);
      // sigma : d_eps^p = dl (alpha_g I1 + q + beta:n/sqrt2) and, on the surface, q = k - alpha I1:
      // the bracket k - (alpha - alpha_g) I1 is >= 0 in exact arithmetic (alpha_g <= alpha,
      // alpha I1 <= k); written this way (and clamped) it has no cancellation, e.g. it is exactly
      // 0 for associated flow without cohesion.
      const double k_new = k + hi * dl;
      const double bracket = k_new - (alpha_ - alpha_g_) * i1_new;
      result.plastic_work = dl * ((bracket > 0.0 ? bracket : 0.0) + beta_n);  // the kernels' max, +0 at 0
      return result;
    }
  }

  // 4. Tension cut-off (finite): the plane I1 = 3 p_t with purely volumetric flow, alone if the
  //    deviator then lies inside the cone, else at the cone/plane corner. The corner exists while
  //    the (hardened) apex lies beyond the plane; otherwise fall through to the apex.
  if (i1_cut < std::numeric_limits<double>::infinity()) {
    const double de_v_plastic = (i1 - i1_cut) / (3.0 * kb);
    if (alpha_ * i1_cut + q - k <= 0.0) {
      const double shift = (i1_cut - i1) / 3.0;
      stress[XX] += shift;
      stress[YY] += shift;
      stress[ZZ] += shift;
      result.regime = Regime::TensionCutoff;
      result.plastic_work = i1_cut / 3.0 * de_v_plastic;
      return result;
    }
    // Corner: I1 = 3 p_t and f = 0 with q = qtr - (G + H_kin) dl, k = k_n + H_iso dl.
    const double dl = (alpha_ * i1_cut + q - k) / (g + hk + hi);
    const double q_new = q - (g + hk) * dl;
    if (q_new >= 0.0) {
      result.regime = Regime::TensionCutoff;
      const double beta_n = radial_return(dl, q_new, i1_cut);
      // sigma : d_eps^p = I1/3 de_v^p + dl (q_new + beta:n/sqrt2), both parts >= 0 for beta = 0.
      result.plastic_work = i1_cut / 3.0 * de_v_plastic + dl * (q_new + beta_n);
      return result;
    }
  }

  // 5. Apex: xi -> 0, so the deviatoric plastic strain is xi_tr / (2 (G + H_kin)) and
  //    d eps_p = q / (G + H_kin); then I1 = k_{n+1} / alpha. Taken as a projection whatever psi
  //    (with psi < phi the flow rule alone cannot reach the apex: the grains separate).
  const double dl = q / (g + hk);
  const double k_new = k + hi * dl;
  const double i1_new = std::fmin(k_new / alpha_, i1_cut);
  const double de_v_plastic = (i1 - i1_new) / (3.0 * kb);
  const double kin = hk / (g + hk);  // d beta = 2 H_kin de^p = H_kin xi / (G + H_kin)
  state.back_stress += kin * xi;
  state.equivalent_plastic_strain += dl;
  const double m = i1_new / 3.0;
  stress = state.back_stress;
  stress[XX] += m;
  stress[YY] += m;
  stress[ZZ] += m;
  result.regime = Regime::Apex;
  // sigma : d_eps^p = m de_v^p + beta_new : xi / (2 (G + H_kin))
  result.plastic_work =
      m * de_v_plastic + double_contract(state.back_stress, xi) / (2.0 * (g + hk));
  return result;
}

}  // namespace talus
