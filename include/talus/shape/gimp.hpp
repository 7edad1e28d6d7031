#pragma once
// GIMP shape functions (generalized interpolation material point, seed 000 eq. 24-27, 30-31):
// the weight of node i is the linear hat N_i averaged over the particle's domain, a box of
// half-width l_p around x_p (chi_p = 1 on the domain, eq. 27):
//     phi_ip = 1/(2 l_p) * integral_{x_p - l_p}^{x_p + l_p} N_i(x) dx                (eq. 24)
// With Phi the antiderivative of the hat this is
//     phi_ip = (Phi(r + l_p) - Phi(r - l_p)) / (2 l_p),   r = x_p - x_i,
//     d phi_ip / d x_p = (N(r + l_p) - N(r - l_p)) / (2 l_p)                            (eq. 25)
// which equals the piecewise-quadratic closed form of eq. 30-31 for l_p <= L/2 and stays exact
// when the domain is wider than a cell (cpGIMP under stretch): the form never divides by a region.
// Everything is in grid units (node spacing 1); half widths are per axis (3D is the tensor
// product, eq. 32).
//
//  uGIMP   l_p = l_p0 for the whole run (eq. 59), l_p0 = (particle edge)/2 = V0^(1/3)/2.
//          l_p0 <= 1/2 for one or more particles per cell, so the support |r| < 1 + l_p fits the
//          3 nodes nearest x_p: round(x_p) - 1 .. round(x_p) + 1.
//  cpGIMP  l_p follows the deformation (eq. 57-58, updated by the solver from the strain
//          increments). The weights accept l_p up to 1 cell (a domain two cells wide, reaching into
//          three cells); wider domains are clamped to 1 cell, which keeps the support inside the 4
//          nodes floor(x_p) - 1 .. floor(x_p) + 2 and the colour blocks race-free.
//
// Both reach one node below the particle's cell and two above (kReachLow = 1, kReachHigh = 2), like
// the quadratic B-spline, so the colour blocks are 8 cells wide (cell_sort.hpp).
#include "talus/shape/linear.hpp"

#include <algorithm>
#include <cmath>

namespace talus {

namespace gimp_detail {

/// Linear hat N(u) = max(0, 1 - |u|) (seed 000 eq. 28).
inline double hat(double u) {
  const double a = std::abs(u);
  return a < 1.0 ? 1.0 - a : 0.0;
}

/// Antiderivative of the hat, Phi(u) = integral_{-inf}^{u} N, from 0 (u <= -1) to 1 (u >= 1).
inline double hat_integral(double u) {
  if (u <= -1.0) return 0.0;
  if (u <= 0.0) return 0.5 * (1.0 + u) * (1.0 + u);
  if (u < 1.0) return 1.0 - 0.5 * (1.0 - u) * (1.0 - u);
  return 1.0;
}

/// Weights of `n` consecutive nodes starting at `base` for a particle at xi with half-width lp.
inline void weights(double xi, double lp, int base, int n, double* w, double* dw) {
  if (lp < 1e-6) {  // a vanishing domain is the material point itself: the linear hat
    for (int a = 0; a < n; ++a) {
      const double r = xi - (base + a);
      w[a] = hat(r);
      dw[a] = std::abs(r) < 1.0 ? (r > 0.0 ? -1.0 : 1.0) : 0.0;
    }
    return;
  }
  const double inv = 0.5 / lp;
  for (int a = 0; a < n; ++a) {
    const double r = xi - (base + a);
    w[a] = (hat_integral(r + lp) - hat_integral(r - lp)) * inv;  // seed 000 eq. 30
    dw[a] = (hat(r + lp) - hat(r - lp)) * inv;                     // seed 000 eq. 31
  }
}

}  // namespace gimp_detail

struct UGimpShape {
  static constexpr int kNodes = 3;
  static constexpr int kReachLow = 1;
  static constexpr int kReachHigh = 2;
  static constexpr bool kUsesDomain = true;
  static constexpr DomainSource kDomain = DomainSource::Initial;
  static constexpr double kMaxHalfWidth = 0.5;  // cells; l_p0 <= 1/2 for >= 1 particle per cell
  static constexpr const char* kName = "ugimp";

  static inline void weights(double xi, double half_width, int& base, double* w, double* dw) {
    base = static_cast<int>(std::floor(xi + 0.5)) - 1;  // nearest node and its two neighbours
    gimp_detail::weights(xi, std::min(half_width, kMaxHalfWidth), base, kNodes, w, dw);
  }
};

struct CpGimpShape {
  static constexpr int kNodes = 4;
  static constexpr int kReachLow = 1;
  static constexpr int kReachHigh = 2;
  static constexpr bool kUsesDomain = true;
  static constexpr DomainSource kDomain = DomainSource::Current;
  static constexpr double kMaxHalfWidth = 1.0;  // cells: the widest domain the 4-node support holds
  static constexpr const char* kName = "cpgimp";

  static inline void weights(double xi, double half_width, int& base, double* w, double* dw) {
    base = static_cast<int>(std::floor(xi)) - 1;
    gimp_detail::weights(xi, std::clamp(half_width, 0.0, kMaxHalfWidth), base, kNodes, w, dw);
  }
};

}  // namespace talus
