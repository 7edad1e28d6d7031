// μ(I) simple shear at constant pressure and imposed rate (docs/mu-i.md, sec. 5).
#include "talus/material/mu_i_shear_test.hpp"

#include "talus/core/error.hpp"
#include "talus/core/tensor.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <ostream>

namespace talus {

std::vector<MuIShearPoint> run_mu_i_shear_test(const MuIShearSpec& spec) {
  const MuI model(spec.material, "material.");
  if (!(spec.pressure > 0.0) || !(spec.strain_increment > 0.0) || spec.increments < 1)
    throw input_error("path: pressure and strain_increment must be > 0 and increments >= 1");
  // J2 squares the stress: a steady shear stress mu(I) p below ~1e-154 Pa squares to a subnormal or
  // to zero, and tau/p comes out wrong or NaN (p = 1e-170 Pa gave tau = 0). The smallest mu(I) is
  // that of the smallest I (mu rises with I); 1e-150 Pa leaves the squares normal with room to spare.
  constexpr double kSmallestShearStress = 1e-150;  // [Pa]
  if (!spec.inertial_numbers.empty()) {
    const double i_min = *std::min_element(spec.inertial_numbers.begin(), spec.inertial_numbers.end());
    const double p_min = kSmallestShearStress / model.friction(i_min);
    if (!(spec.pressure >= p_min))
      throw_out_of_range("path.", "pressure", spec.pressure,
                         "p >= " + number_g(p_min) + " Pa (the steady shear stress mu(I) p at I = " + number_g(i_min) +
                             " must be >= 1e-150 Pa, or squaring it underflows)");
  }
  std::vector<MuIShearPoint> points;
  for (const double i : spec.inertial_numbers) {
    MuIShearPoint pt;
    pt.inertial_number = i;
    // Jop et al. 2006: the inertial number solved for the shear rate
    pt.shear_rate = i * std::sqrt(spec.pressure / spec.material.grain_density) / spec.material.grain_diameter;
    pt.dt = spec.strain_increment / pt.shear_rate;
    Sym6 stress = -spec.pressure * identity6();
    Sym6 d_eps = Sym6::Zero();
    d_eps[XY] = 0.5 * spec.strain_increment;  // tensor component of gamma_xy
    double tau_previous = 0.0;
    for (int n = 0; n < spec.increments; ++n) {
      tau_previous = std::sqrt(j2(stress));
      const MuIResult r = model.update(stress, d_eps, pt.dt);
      pt.plastic_shear_rate = r.plastic_shear_strain / pt.dt;
    }
    pt.pressure = -trace(stress) / 3.0;
    pt.shear_stress = std::sqrt(j2(stress));
    pt.friction = pt.shear_stress / pt.pressure;
    pt.friction_analytic = model.friction(i);  // Jop et al. 2006, the friction law
    pt.relative_error = pt.friction / pt.friction_analytic - 1.0;
    pt.last_change = std::abs(pt.shear_stress - tau_previous) / pt.shear_stress;
    points.push_back(pt);
  }
  return points;
}

std::string mu_i_shear_strain_shortfall(const MuIShearSpec& spec) {
  if (spec.inertial_numbers.empty()) return {};
  const MuI model(spec.material, "material.");
  const double i_max = *std::max_element(spec.inertial_numbers.begin(), spec.inertial_numbers.end());
  const double tau = model.friction(i_max) * spec.pressure;
  const double needed = tau / model.shear_modulus();  // engineering shear strain of the elastic approach
  const double given = spec.strain_increment * spec.increments;
  if (given >= needed) return {};
  char text[512];
  std::snprintf(text, sizeof text,
                "path.increments x path.strain_increment = %.3g is below the shear strain %.3g that the elastic "
                "response needs to reach the steady stress mu(I) p = %.3g Pa at I = %.3g (shear modulus %.3g Pa): "
                "those samples never flow, and tau/p reads below mu(I); raise the increments or the strain increment",
                given, needed, tau, i_max, model.shear_modulus());
  return text;
}

void write_mu_i_shear_csv(std::ostream& out, const std::vector<MuIShearPoint>& points) {
  out << "I,shear_rate,dt,p,tau,tau_over_p,mu_analytic,relative_error,plastic_shear_rate,last_change\n";
  char buffer[512];
  for (const MuIShearPoint& p : points) {
    std::snprintf(buffer, sizeof buffer, "%.17g,%.17g,%.17g,%.17g,%.17g,%.17g,%.17g,%.6e,%.17g,%.3e\n",
                  p.inertial_number, p.shear_rate, p.dt, p.pressure, p.shear_stress, p.friction,
                  p.friction_analytic, p.relative_error, p.plastic_shear_rate, p.last_change);
    out << buffer;
  }
}

}  // namespace talus
