#pragma once
// The two ingredients of the MLS fit (Edo & Matsubara 2015, eq. 38-46): the weight W(r, h) and the polynomial
// basis F(x). Header-only: both are evaluated once per neighbour in the smoother's inner loop.
#include <array>
#include <cmath>

namespace talus {

/// Polynomial degree of the MLS basis. In 3D: linear 4, quadratic 10, cubic 20 terms.
enum class MlsBasis { Linear = 1, Quadratic = 2, Cubic = 3 };

const char* to_string(MlsBasis basis);

/// Number of monomials of total degree <= degree in `axes` variables: C(axes + degree, degree).
constexpr int mls_term_count(int degree, int axes) {
  int n = 1;
  for (int i = 1; i <= degree; ++i) n = n * (axes + i) / i;
  return n;
}
static_assert(mls_term_count(1, 3) == 4 && mls_term_count(2, 3) == 10 && mls_term_count(3, 3) == 20);
static_assert(mls_term_count(3, 1) == 4);  // the paper's 1D cubic fit

/// Cubic-spline weight of Edo & Matsubara 2015, eq. 39 in its standard form (docs/theory.md), s = r / h:
///   2/3 - 4 s^2 + 4 s^3            0 <= s < 1/2
///   4/3 - 4 s + 4 s^2 - 4/3 s^3    1/2 <= s < 1
///   0                              s >= 1
/// (the OCR of the paper drops the square in the first branch; this form is continuous with a
/// continuous slope at s = 1/2 and vanishes with zero slope at s = 1).
inline double mls_weight(double s) {
  if (s < 0.5) return 2.0 / 3.0 - 4.0 * s * s + 4.0 * s * s * s;
  if (s < 1.0) return 4.0 / 3.0 - 4.0 * s + 4.0 * s * s - 4.0 / 3.0 * s * s * s;
  return 0.0;
}

/// F(u): the monomials of u (Axes coordinates) up to total degree Degree, constant term first:
/// 1, u_a, u_a u_b (a <= b), u_a u_b u_c (a <= b <= c). The smoother evaluates it at positions
/// relative to the particle and scaled by the radius (|u| < 1), so F(0) = (1, 0, ..., 0).
/// T is double, or a vector of lanes (the smoother's groups): the same products in the same order.
template <int Degree, int Axes, class T>
inline void mls_basis(const T* u, T* F) {
  int n = 0;
  F[n++] = T{} + 1.0;  // 1 in every lane
  for (int a = 0; a < Axes; ++a) F[n++] = u[a];
  if constexpr (Degree >= 2)
    for (int a = 0; a < Axes; ++a)
      for (int b = a; b < Axes; ++b) F[n++] = u[a] * u[b];
  if constexpr (Degree >= 3)
    for (int a = 0; a < Axes; ++a)
      for (int b = a; b < Axes; ++b)
        for (int c = b; c < Axes; ++c) F[n++] = u[a] * u[b] * u[c];
}

}  // namespace talus
