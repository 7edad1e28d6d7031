#pragma once
// Isotropic linear elasticity in incremental (hypoelastic) form: d_sigma = D : d_eps =
// lambda tr(d_eps) I + 2 G d_eps (Edo & Matsubara 2015, eq. 34). The Jaumann rotation of the stress
// is the material pass's, before this update (tensor.hpp, rotate_objectively: Hughes-Winget).
#include "talus/core/tensor.hpp"
#include "talus/material/elastic_moduli.hpp"

namespace talus {

struct LinearElastic {
  double lambda = 0.0;  // Lame's first parameter
  double shear = 0.0;   // G

  static LinearElastic from_moduli(const ElasticModuli& moduli) {
    LinearElastic m;
    m.shear = moduli.shear();
    m.lambda = moduli.lame();
    return m;
  }
  double bulk() const { return lambda + 2.0 / 3.0 * shear; }

  /// Stress increment for a strain increment (tensor shear components).
  void add_increment(Sym6& s, const Sym6& d_eps) const {
    const double lt = lambda * trace(d_eps);
    for (int i = 0; i < 3; ++i) s[i] += lt + 2.0 * shear * d_eps[i];
    for (int i = 3; i < 6; ++i) s[i] += 2.0 * shear * d_eps[i];
  }

  /// Stored elastic energy density 1/2 sigma : C^-1 : sigma = p^2 / (2K) + s:s / (4G).
  double energy_density(const Sym6& s) const {
    const double p = trace(s) / 3.0;
    const Sym6 dev = deviator(s);
    return p * p / (2.0 * bulk()) + double_contract(dev, dev) / (4.0 * shear);
  }
};

}  // namespace talus
