#pragma once
// GIMP shape functions (generalized interpolation material point, Edo & Matsubara 2015, eq. 24-27, 30-31):
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

/// Linear hat N(u) = max(0, 1 - |u|) (Edo & Matsubara 2015, eq. 28).
[[gnu::always_inline]] inline double hat(double u) {
  const double t = 1.0 - std::abs(u);
  return t > 0.0 ? t : 0.0;  // not std::fmax: that is a libm call here (its NaN rules)
}

/// Antiderivative of the hat, Phi(u) = integral_{-inf}^{u} N, from 0 (u <= -1) to 1 (u >= 1).
/// Written without branches (clamp, then select): the weights run 6-8 times per particle and axis
/// in each transfer pass, and the branchy form mispredicted (uGIMP was 28% slower than the
/// B-spline on the same 27 nodes). Each branch is monotone in c, so weights stay >= 0.
[[gnu::always_inline]] inline double hat_integral(double u) {
  const double c = std::clamp(u, -1.0, 1.0);
  const double below = 0.5 * (1.0 + c) * (1.0 + c);
  const double above = 1.0 - 0.5 * (1.0 - c) * (1.0 - c);
  return c <= 0.0 ? below : above;
}

/// Weights of `n` consecutive nodes starting at `base` for a particle at xi with half-width lp.
/// Always inlined, like the shapes' weights(): as a call it was a quarter of a cpGIMP step.
[[gnu::always_inline]] inline void weights(double xi, double lp, int base, int n, double* w, double* dw) {
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
    w[a] = (hat_integral(r + lp) - hat_integral(r - lp)) * inv;  // Edo & Matsubara 2015, eq. 30
    dw[a] = (hat(r + lp) - hat(r - lp)) * inv;                     // Edo & Matsubara 2015, eq. 31
  }
}

/// The same weights for a domain at most half a cell wide (lp <= 1/2) on the 3 nodes nearest xi,
/// from the region formulas of Edo & Matsubara 2015, eq. 30-31 instead of the antiderivative: with u = xi -
/// nearest node in [-1/2, 1/2),
///     w_low  = -u              (u <= -lp),   (lp - u)^2 / (4 lp)   (|u| < lp),   0 (u >= lp)
///     w_high =  u              (u >=  lp),   (lp + u)^2 / (4 lp)   (|u| < lp),   0 (u <= -lp)
///     w_mid  = 1 - w_low - w_high   (= 1 - (u^2 + lp^2)/(2 lp) for |u| < lp, 1 - |u| otherwise)
/// and the derivatives likewise. About as cheap as the quadratic B-spline's weights; the general
/// form above cost uGIMP 36% of its step against the B-spline on the same 27 nodes.
[[gnu::always_inline]] inline void narrow_weights(double xi, double lp, int& base, double* w, double* dw) {
  const double nearest = std::floor(xi + 0.5);
  base = static_cast<int>(nearest) - 1;
  const double u = xi - nearest;
  if (lp < 1e-6) {  // the material point itself: the linear hat on the two nodes around xi
    w[0] = u < 0.0 ? -u : 0.0;
    w[2] = u > 0.0 ? u : 0.0;
    dw[0] = u < 0.0 ? -1.0 : 0.0;
    dw[2] = u > 0.0 ? 1.0 : 0.0;
  } else {
    const double inv = 0.25 / lp;
    const double lo = lp - u, hi = lp + u;  // both > 0 inside the overlap |u| < lp
    const bool low_only = u <= -lp, high_only = u >= lp;
    w[0] = low_only ? -u : (high_only ? 0.0 : lo * lo * inv);
    w[2] = high_only ? u : (low_only ? 0.0 : hi * hi * inv);
    dw[0] = low_only ? -1.0 : (high_only ? 0.0 : -2.0 * lo * inv);
    dw[2] = high_only ? 1.0 : (low_only ? 0.0 : 2.0 * hi * inv);
  }
  w[1] = 1.0 - w[0] - w[2];
  dw[1] = -dw[0] - dw[2];
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

  [[gnu::always_inline]] static inline void weights(double xi, double half_width, int& base, double* w, double* dw) {
    gimp_detail::narrow_weights(xi, std::min(half_width, kMaxHalfWidth), base, w, dw);  // nearest node +-1
  }
};

/// cpGIMP for a particle whose domain is at most half a cell wide on every axis (the usual state:
/// l_p0 = 1/4 at 2 particles per cell and axis): the support |r| < 1 + l_p then fits the 3 nodes
/// nearest x_p, as for uGIMP, and the 4th node of CpGimpShape has weight and gradient exactly 0.
/// The transfers use it per particle (Stencil's ParticleStencil): the same sums without the zero
/// terms (and the weights from the region formulas, equal to round-off): 27 nodes instead of 64.
struct CpGimpNarrowShape {
  static constexpr int kNodes = 3;
  static constexpr int kReachLow = 1;
  static constexpr int kReachHigh = 2;
  static constexpr bool kUsesDomain = true;
  static constexpr DomainSource kDomain = DomainSource::Current;
  static constexpr double kMaxHalfWidth = 0.5;  // cells
  static constexpr const char* kName = "cpgimp";

  [[gnu::always_inline]] static inline void weights(double xi, double half_width, int& base, double* w, double* dw) {
    // nearest node +-1: inside CpGimpShape's floor(xi) - 1 .. floor(xi) + 2
    gimp_detail::narrow_weights(xi, std::clamp(half_width, 0.0, kMaxHalfWidth), base, w, dw);
  }
};

struct CpGimpShape {
  using Narrow = CpGimpNarrowShape;  // for particles with every half width <= Narrow::kMaxHalfWidth
  static constexpr int kNodes = 4;
  static constexpr int kReachLow = 1;
  static constexpr int kReachHigh = 2;
  static constexpr bool kUsesDomain = true;
  static constexpr DomainSource kDomain = DomainSource::Current;
  static constexpr double kMaxHalfWidth = 1.0;  // cells: the widest domain the 4-node support holds
  static constexpr const char* kName = "cpgimp";

  [[gnu::always_inline]] static inline void weights(double xi, double half_width, int& base, double* w, double* dw) {
    base = static_cast<int>(std::floor(xi)) - 1;
    gimp_detail::weights(xi, std::clamp(half_width, 0.0, kMaxHalfWidth), base, kNodes, w, dw);
  }
};

}  // namespace talus
