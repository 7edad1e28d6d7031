#pragma once
// Quadratic B-spline shape functions (Steffen, Kirby & Berzins 2008): C1 weights on the 3 nodes
// nearest the particle, so a particle crossing a cell face sees no jump in the force gradient (the
// cell-crossing error of linear MPM, Edo & Matsubara 2015, sec. 4). In grid units, with i the nearest node and
// u = x_p - x_i in [-1/2, 1/2):
//     N_{i-1} = (1/2 - u)^2 / 2,   N_i = 3/4 - u^2,   N_{i+1} = (1/2 + u)^2 / 2.
// The support reaches one node below the particle's cell and two above (kReachLow = 1,
// kReachHigh = 2); 3D is the tensor product (Edo & Matsubara 2015, eq. 32). Same interface as LinearShape.
#include "talus/shape/linear.hpp"

#include <cmath>

namespace talus {

struct QuadraticBSplineShape {
  static constexpr int kNodes = 3;
  static constexpr int kReachLow = 1;
  static constexpr int kReachHigh = 2;
  static constexpr bool kUsesDomain = false;
  static constexpr DomainSource kDomain = DomainSource::None;
  static constexpr const char* kName = "bspline2";

  static inline void weights(double xi, double /*half_width*/, int& base, double* w, double* dw) {
    const double nearest = std::floor(xi + 0.5);
    base = static_cast<int>(nearest) - 1;
    const double u = xi - nearest;  // in [-1/2, 1/2)
    const double lo = 0.5 - u, hi = 0.5 + u;
    w[0] = 0.5 * lo * lo;
    w[1] = 0.75 - u * u;
    w[2] = 0.5 * hi * hi;
    dw[0] = -lo;
    dw[1] = -2.0 * u;
    dw[2] = hi;
  }
};

}  // namespace talus
