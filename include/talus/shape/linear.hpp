#pragma once
// Linear (standard MPM) shape functions, Edo & Matsubara 2015, eq. 28-29: the 1D hat N_i(x) = 1 - |x - x_i| / L,
// 3D weights as the tensor product (Edo & Matsubara 2015, eq. 32).
//
// The interface every shape function implements (the GIMP and B-spline functions follow it):
//   kNodes            nodes per axis in a particle's support
//   kReachLow/High    the support spans cells [c - kReachLow, c + kReachHigh] in node indices,
//                     c = floor(xi) the particle's cell; sets the colour-block size (cell_sort.hpp)
//   kUsesDomain       whether the weights depend on the particle's half-width (GIMP)
//   kDomain           where that half-width comes from (DomainSource below)
//   weights(xi, half_width, base, w, dw)
//                     xi in grid units (node spacing 1); fills the kNodes weights and their
//                     derivatives d/dxi, starting at node index `base`.
#include <cmath>

namespace talus {

/// Which half-width the transfers pass to a shape function's weights().
enum class DomainSource {
  None,     // material point (linear, B-spline): half width unused
  Initial,  // uGIMP: l_p0 = V0^(1/3)/2, fixed (Edo & Matsubara 2015, eq. 59)
  Current,  // cpGIMP: the particle's current half widths (ParticleStore::domain, eq. 57-58)
};

struct LinearShape {
  static constexpr int kNodes = 2;
  static constexpr int kReachLow = 0;
  static constexpr int kReachHigh = 1;
  static constexpr bool kUsesDomain = false;
  static constexpr DomainSource kDomain = DomainSource::None;
  static constexpr const char* kName = "linear";

  static inline void weights(double xi, double /*half_width*/, int& base, double* w, double* dw) {
    const double cell = std::floor(xi);
    base = static_cast<int>(cell);
    const double f = xi - cell;  // local coordinate in [0, 1)
    w[0] = 1.0 - f;              // Edo & Matsubara 2015, eq. 28
    w[1] = f;
    dw[0] = -1.0;                // Edo & Matsubara 2015, eq. 29 (per unit grid spacing)
    dw[1] = 1.0;
  }
};

}  // namespace talus
