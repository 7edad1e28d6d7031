#pragma once
// μ(I) rheology of dense granular flow (Jop, Forterre & Pouliquen 2006; GDR MiDi 2004) in the
// elasto-plastic form of Dunatunga & Kamrin 2015, which fits an explicit MPM update. Theory,
// derivation of the closed-form return and verification: docs/mu-i.md.
//
// Sign convention as in drucker_prager.hpp: stress positive in tension, pressure p = -tr(sigma)/3,
// equivalent shear stress tau = sqrt(J2) = |s| / sqrt(2) (s the deviator). Then
//     mu(I) = mu_s + (mu_2 - mu_s) / (1 + I0 / I)             (Jop et al. 2006, the friction law)
//     I = gdot_p d / sqrt(p / rho_s)                          (Jop et al. 2006, the inertial number)
// with gdot_p the equivalent plastic shear rate, gdot_p = sqrt(2 D^p : D^p) (the engineering
// plastic shear rate in simple shear). Plastic flow is deviatoric (no dilatancy, Dunatunga &
// Kamrin 2015 sec. 2.2) and coaxial with s.
//
// Update per particle and step (Dunatunga & Kamrin 2015, sec. 3.2), after the objective rotation:
//  1. elastic trial  sigma_tr = sigma + lambda tr(d_eps) I + 2 G d_eps;
//  2. p_tr <= 0: the grains have lost contact ("disconnected"): sigma = 0;
//  3. tau_tr <= mu_s p_tr: elastic, sigma = sigma_tr;
//  4. otherwise flowing: p = p_tr and the deviator is scaled down to tau that solves
//         tau = mu(I) p,   I = gdot_p d / sqrt(p / rho_s),   gdot_p = (tau_tr - tau) / (G dt),
//     a quadratic in mu = tau / p whose smaller root lies in (mu_s, min(tau_tr / p, mu_2)) for
//     every dt > 0: the return never overshoots, so the update is stable for any time step
//     (docs/mu-i.md sec. 3 derives the root and its cancellation-free form).
// update() allocates nothing, makes no virtual call and has no iteration: three square roots and
// three divisions on the flowing path, one square root on the elastic path.
#include "talus/core/types.hpp"
#include "talus/material/elastic_moduli.hpp"

#include <cmath>
#include <numbers>
#include <string_view>

namespace talus {

/// Material constants, SI units. Defaults: the glass beads of Jop, Forterre & Pouliquen 2006
/// (their sec. "Comparison with experiments": mu_s = tan 20.9 deg, mu_2 = tan 32.76 deg,
/// I0 = 0.279, d = 0.53 mm, rho_s = 2450 kg/m^3). young and poisson have no default.
struct MuIParameters {
  double young = 0.0;    ///< E > 0 [Pa]
  double poisson = 0.0;  ///< nu in [0, 0.5)
  double mu_s = 0.3818628674187188;        ///< tan(20.9 deg), >= 0: the static friction coefficient
  double mu_2 = 0.6434683848584607;        ///< tan(32.76 deg), > mu_s: the limit as I -> infinity
  double i0 = 0.279;                      ///< I0 > 0
  double grain_diameter = 0.53e-3;        ///< d > 0 [m]
  double grain_density = 2450.0;          ///< rho_s > 0 [kg/m^3]
  /// E and nu, for the moduli the model derives from them (elastic_moduli.hpp).
  ElasticModuli moduli() const { return {young, poisson}; }
};

struct MuIResult {
  /// Energy dissipated per unit volume in this increment [J/m^3], >= 0: flowing, tau gdot_p dt with
  /// the returned tau (as Drucker-Prager counts it; docs/mu-i.md sec. 3); disconnected, what the
  /// step's work left of the stored energy, E(sigma_n) + sigma_n : d_eps, or 0 where the explicit
  /// work overshot the stored energy (that overshoot is energy the explicit step made, not negative
  /// dissipation: the budget's gap shows it, docs/mu-i.md sec. 3).
  double plastic_work = 0.0;
  /// Equivalent plastic shear strain of this increment, gdot_p dt >= 0.
  double plastic_shear_strain = 0.0;
  enum class Regime { Elastic, Flowing, Disconnected } regime = Regime::Elastic;
};

class MuI {
 public:
  /// Validates the parameters; throws talus::input_error naming `key_prefix` + the parameter
  /// (mu_s, mu_2, i0, grain_diameter, grain_density, young, poisson) and its allowed range.
  explicit MuI(const MuIParameters& parameters, std::string_view key_prefix = "");

  /// Elastic trial step, then the μ(I) return for time step dt > 0 (see top). `stress` must
  /// already be rotated to the end of the step (objective update).
  MuIResult update(Sym6& stress, const Sym6& strain_increment, double dt) const;

  /// mu(I) = mu_s + (mu_2 - mu_s) I / (I + I0) (Jop et al. 2006, the friction law), I >= 0.
  double friction(double inertial_number) const {
    return parameters_.mu_s + delta_mu_ * inertial_number / (inertial_number + parameters_.i0);
  }
  /// I = gdot d / sqrt(p / rho_s) (Jop et al. 2006, the inertial number), p > 0.
  double inertial_number(double shear_rate, double pressure) const {
    return shear_rate * parameters_.grain_diameter / std::sqrt(pressure / parameters_.grain_density);
  }

  /// Stored elastic energy per unit volume, p^2/2K + tau^2/2G (the mu(I) vector kernel repeats its
  /// operations for disconnected particles: change both together).
  double elastic_energy_density(const Sym6& stress) const {
    const double m = (stress[XX] + stress[YY] + stress[ZZ]) / 3.0;
    const double dxx = stress[XX] - m, dyy = stress[YY] - m, dzz = stress[ZZ] - m;
    const double tau2 = 0.5 * (dxx * dxx + dyy * dyy + dzz * dzz) + stress[YZ] * stress[YZ] +
                        stress[XZ] * stress[XZ] + stress[XY] * stress[XY];
    return 0.5 * (m * m / bulk_ + tau2 / shear_);
  }

  const MuIParameters& parameters() const { return parameters_; }
  double shear_modulus() const { return shear_; }
  double bulk_modulus() const { return bulk_; }
  double lame_lambda() const { return lame_; }
  double friction_rise() const { return delta_mu_; }     ///< mu_2 - mu_s
  double rate_constant() const { return rate_constant_; }  ///< d sqrt(rho_s) / G

 private:
  MuIParameters parameters_;
  double shear_ = 0.0, bulk_ = 0.0, lame_ = 0.0;
  double delta_mu_ = 0.0;      // mu_2 - mu_s
  double rate_constant_ = 0.0;  // d sqrt(rho_s) / G: B = rate_constant sqrt(p) / dt (docs/mu-i.md)
};

inline MuIResult MuI::update(Sym6& stress, const Sym6& strain_increment, double dt) const {
  // The vector kernel of solver/material_kernels.cpp does steps 1-4 lane by lane in exactly
  // these operations; change both together (IsaPaths compares them bit for bit).
  // 1. Elastic trial (plain arrays, as in DruckerPrager::update, for the same reason).
  const double de_v = strain_increment[XX] + strain_increment[YY] + strain_increment[ZZ];
  double trial[6];
  for (int c = 0; c < 6; ++c) trial[c] = stress[c] + 2.0 * shear_ * strain_increment[c];
  for (int c = 0; c < 3; ++c) trial[c] += lame_ * de_v;
  const double mean = (trial[XX] + trial[YY] + trial[ZZ]) / 3.0;
  const double p = -mean;
  MuIResult result;
  double s[6];
  for (int c = 0; c < 6; ++c) s[c] = trial[c] - (c < 3 ? mean : 0.0);
  // 2. Disconnected (Dunatunga & Kamrin 2015, sec. 3.2): no contact pressure, no stress. The
  //    grid forces of this step came from the start-of-step stress sigma_n and did the work
  //    -sigma_n : d_eps on the grains; what the particle held beyond that, E(sigma_n) + sigma_n : d_eps,
  //    is released and counted as dissipated (docs/mu-i.md sec. 3, "Dissipation"). Below zero the
  //    explicit work overshot the stored energy (p crossed zero within the step, and sigma_n worked
  //    over all of it): energy the step made, not dissipation, so none is counted and the budget's
  //    gap shows it, as it shows the elastic steps' second-order term. (NaN passes, for the guards.)
  if (!(p > 0.0)) {
    double work = 0.0;
    for (int c = 0; c < 6; ++c) work += (c < 3 ? 1.0 : 2.0) * stress[c] * strain_increment[c];
    const double released = elastic_energy_density(stress) + work;
    result.plastic_work = released < 0.0 ? 0.0 : released;
    for (int c = 0; c < 6; ++c) stress[c] = 0.0;
    result.regime = MuIResult::Regime::Disconnected;
    return result;
  }
  const double tau_trial = std::sqrt(0.5 * (s[XX] * s[XX] + s[YY] * s[YY] + s[ZZ] * s[ZZ]) + s[YZ] * s[YZ] +
                                     s[XZ] * s[XZ] + s[XY] * s[XY]);
  const double mu_s = parameters_.mu_s, mu_2 = parameters_.mu_2, i0 = parameters_.i0;
  // 3. Below the static yield cone: elastic.
  if (tau_trial <= mu_s * p) {
    for (int c = 0; c < 6; ++c) stress[c] = trial[c];
    return result;
  }
  // 4. Flowing: with S = tau_tr / p and I = B (S - mu), B = d sqrt(rho_s p) / (G dt), the
  //    condition (mu - mu_s)(I + I0) = (mu_2 - mu_s) I reads
  //        B mu^2 - b mu + c = 0,  b = B (S + mu_2) + I0,  c = B S mu_2 + mu_s I0,
  //    and its smaller root, written 2c / (b + sqrt(disc)), has no cancellation; disc is
  //    expanded into a sum of non-negative terms (S > mu_s) for the same reason (docs/mu-i.md).
  const double ratio = tau_trial / p;
  const double big_b = rate_constant_ * std::sqrt(p) / dt;
  const double b = big_b * (ratio + mu_2) + i0;
  const double c = big_b * ratio * mu_2 + mu_s * i0;
  const double gap = ratio - mu_2;
  const double disc = big_b * big_b * gap * gap + 2.0 * big_b * i0 * (ratio - mu_s + delta_mu_) + i0 * i0;
  const double mu = 2.0 * c / (b + std::sqrt(disc));
  const double tau = mu * p;
  const double scale = mu / ratio;  // tau / tau_tr, in (0, 1)
  for (int c6 = 0; c6 < 6; ++c6) stress[c6] = scale * s[c6] + (c6 < 3 ? mean : 0.0);
  result.regime = MuIResult::Regime::Flowing;
  result.plastic_shear_strain = (tau_trial - tau) / shear_;  // gdot_p dt
  // sigma_{n+1} : d_eps^p = tau gdot_p dt, as Drucker-Prager counts it (docs/mu-i.md sec. 3).
  result.plastic_work = tau * result.plastic_shear_strain;
  return result;
}

}  // namespace talus
