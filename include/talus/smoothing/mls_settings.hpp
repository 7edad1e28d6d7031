#pragma once
// The settings of the MLS strain-increment smoother (Edo & Matsubara 2015, eq. 38-46), as the scene gives them.
#include "talus/smoothing/mls_basis.hpp"

#include <array>

namespace talus {

/// Where the fit is centred. Particle: Edo & Matsubara's (2015) own fit, one per particle, the
/// reference. Cell: one fit per cell, centred at the cell's centre and evaluated at each of its
/// particles (a cheaper variant; its accuracy against the per-particle fit: docs/verification.md,
/// "MLS, one fit per cell"). Reused: the particle fit, its weights kept and reused in later steps
/// until the material has strained by `reuse_strain` since the fit (a cheaper variant; docs/verification.md,
/// "MLS, the particle fit's weights reused").
enum class MlsVariant { Particle, Cell, Reused };

const char* to_string(MlsVariant variant);

struct MlsSettings {
  MlsBasis basis = MlsBasis::Linear;
  MlsVariant variant = MlsVariant::Particle;
  double radius_factor = 2.0;              // h = radius_factor * cell size
  /// The axes the basis spans. A body one or two particle layers thick along an axis cannot
  /// resolve a quadratic along it (A is singular); leaving that axis out fits a 1D or 2D
  /// polynomial and averages across it (Edo & Matsubara's (2015) own tests are 1D).
  std::array<bool, 3> axes{true, true, true};
  double min_rcond = 1e-10;                // guard on A's reciprocal condition number (1-norm estimate)
  /// MlsVariant::Reused: the fits are redone once the sum, over the steps since the fit, of each
  /// step's largest strain increment (Frobenius norm, unsmoothed) exceeds this.
  double reuse_strain = 1e-2;
};

}  // namespace talus
