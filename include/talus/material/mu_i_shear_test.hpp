#pragma once
// Element test of the μ(I) model: simple shear at constant pressure p and imposed shear rate
// gdot, one run per inertial number I, gdot = I sqrt(p / rho_s) / d (Jop et al. 2006, the inertial number).
// Each run starts at -p I, applies d_eps_xy = gdot dt / 2 per increment (no spin, so the
// pressure stays exactly p: μ(I) flow is isochoric) until the stress is steady, then compares
// tau / p with mu(I) (Jop et al. 2006, the friction law). `talus element-test SPEC.json --out FILE.csv`
// runs it for a spec whose material has "model": "mu_i" (docs/mu-i.md has the spec and columns).
#include "talus/material/mu_i.hpp"

#include <iosfwd>
#include <string>
#include <vector>

namespace talus {

struct MuIShearSpec {
  MuIParameters material;
  double pressure = 1.0e3;                 ///< p > 0 [Pa], compression positive
  std::vector<double> inertial_numbers;    ///< imposed I, each > 0
  double strain_increment = 5.0e-5;        ///< engineering shear strain per increment, gdot dt
  int increments = 2000;                   ///< increments per run
};

struct MuIShearPoint {
  double inertial_number = 0.0;       ///< imposed I
  double shear_rate = 0.0;            ///< imposed gdot [1/s]
  double dt = 0.0;                    ///< strain_increment / gdot [s]
  double pressure = 0.0;              ///< -tr(sigma)/3 at the end [Pa]
  double shear_stress = 0.0;          ///< tau = sqrt(J2) at the end [Pa]
  double friction = 0.0;              ///< tau / p
  double friction_analytic = 0.0;     ///< mu(I)
  double relative_error = 0.0;        ///< friction / friction_analytic - 1
  double plastic_shear_rate = 0.0;    ///< gdot_p of the last increment [1/s]
  double last_change = 0.0;           ///< |tau_n - tau_{n-1}| / tau_n at the last increment
};

std::vector<MuIShearPoint> run_mu_i_shear_test(const MuIShearSpec& spec);

/// Why the spec's total shear strain, increments x strain_increment, cannot bring every sample to
/// steady flow: below tau / G for the largest steady stress tau = mu(I_max) p the sample stays
/// elastic, and tau/p reads far below mu(I) (p = 1e8 Pa with the shipped spec: 99% low, every
/// number finite). Empty when the strain suffices.
std::string mu_i_shear_strain_shortfall(const MuIShearSpec& spec);

/// CSV with a header row: I,shear_rate,dt,p,tau,tau_over_p,mu_analytic,relative_error,plastic_shear_rate,last_change
void write_mu_i_shear_csv(std::ostream& out, const std::vector<MuIShearPoint>& points);

}  // namespace talus
