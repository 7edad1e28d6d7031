// μ(I) model: parameter checks and derived constants; the update is inline in mu_i.hpp.
#include "talus/material/mu_i.hpp"

#include "talus/core/error.hpp"

#include <cmath>
#include <string>

namespace talus {

namespace {

/// A friction coefficient from here up (tan 63.4 degrees) is likelier an angle written in degrees.
constexpr double kLikelyDegrees = 2.0;

void validate(const MuIParameters& p, std::string_view prefix) {
  // Written as !(inside) so that NaN is rejected too.
  if (!(p.young > 0.0 && std::isfinite(p.young))) throw_out_of_range(prefix, "young", p.young, "E > 0 (Pa, finite)");
  if (!(p.poisson >= 0.0 && p.poisson < 0.5)) throw_out_of_range(prefix, "poisson", p.poisson, "[0, 0.5)");
  if (!(p.mu_s >= 0.0 && std::isfinite(p.mu_s))) throw_out_of_range(prefix, "mu_s", p.mu_s, "mu_s >= 0 (finite)");
  // (mu_s = 35 meant as degrees was reported as mu_2's fault alone)
  if (!(p.mu_2 > p.mu_s && std::isfinite(p.mu_2)))
    throw_out_of_range(prefix, "mu_2", p.mu_2,
                       "mu_2 > mu_s = " + number_g(p.mu_s) + " (finite)" +
                           (p.mu_s >= kLikelyDegrees ? "; mu_s and mu_2 are friction coefficients (tan of the angle), "
                                                       "not angles in degrees"
                                                     : ""));
  if (!(p.i0 > 0.0 && std::isfinite(p.i0))) throw_out_of_range(prefix, "i0", p.i0, "I0 > 0 (finite)");
  if (!(p.grain_diameter > 0.0 && std::isfinite(p.grain_diameter)))
    throw_out_of_range(prefix, "grain_diameter", p.grain_diameter, "d > 0 (m, finite)");
  if (!(p.grain_density > 0.0 && std::isfinite(p.grain_density)))
    throw_out_of_range(prefix, "grain_density", p.grain_density, "rho_s > 0 (kg/m^3, finite)");
}

}  // namespace

MuI::MuI(const MuIParameters& parameters, std::string_view key_prefix) : parameters_(parameters) {
  validate(parameters_, key_prefix);
  const ElasticModuli moduli = parameters_.moduli();
  shear_ = moduli.shear();
  bulk_ = moduli.bulk();
  lame_ = moduli.lame_from_bulk();
  delta_mu_ = parameters_.mu_2 - parameters_.mu_s;
  rate_constant_ = parameters_.grain_diameter * std::sqrt(parameters_.grain_density) / shear_;
}

}  // namespace talus
