#pragma once
// Operations on symmetric tensors stored as Voigt 6-vectors of tensor components (types.hpp).
#include "talus/core/types.hpp"

#include <cmath>

namespace talus {

inline double trace(const Sym6& s) { return s[XX] + s[YY] + s[ZZ]; }

inline Sym6 deviator(const Sym6& s) {
  Sym6 d = s;
  const double p = trace(s) / 3.0;
  d[XX] -= p;
  d[YY] -= p;
  d[ZZ] -= p;
  return d;
}

/// Full double contraction a:b of two symmetric tensors (shear entries counted twice).
inline double double_contract(const Sym6& a, const Sym6& b) {
  return a[XX] * b[XX] + a[YY] * b[YY] + a[ZZ] * b[ZZ] +
         2.0 * (a[YZ] * b[YZ] + a[XZ] * b[XZ] + a[XY] * b[XY]);
}

/// Second invariant of the deviator, J2 = 1/2 s:s.
inline double j2(const Sym6& s) {
  const Sym6 d = deviator(s);
  return 0.5 * double_contract(d, d);
}

/// Identity tensor in Voigt form.
inline Sym6 identity6() {
  Sym6 i;
  i << 1.0, 1.0, 1.0, 0.0, 0.0, 0.0;
  return i;
}

inline Mat3 to_matrix(const Sym6& s) {
  Mat3 m;
  m << s[XX], s[XY], s[XZ],
       s[XY], s[YY], s[YZ],
       s[XZ], s[YZ], s[ZZ];
  return m;
}

inline Sym6 from_matrix(const Mat3& m) {
  Sym6 s;
  s << m(0, 0), m(1, 1), m(2, 2), 0.5 * (m(1, 2) + m(2, 1)), 0.5 * (m(0, 2) + m(2, 0)),
      0.5 * (m(0, 1) + m(1, 0));
  return s;
}

/// Forward-Euler form of the Jaumann rotation (kept as the first-order reference that
/// rotate_objectively() is tested against; the solver uses rotate_objectively):
/// sigma <- sigma + dW sigma - sigma dW, with dW the spin increment (w_yz, w_xz, w_xy),
/// dW_ij = dt/2 (dv_i/dx_j - dv_j/dx_i). Written out so that it vectorises and allocates nothing.
inline void jaumann_rotate(Sym6& s, double w_yz, double w_xz, double w_xy) {
  // dW as a full antisymmetric matrix: W(0,1) = w_xy, W(0,2) = w_xz, W(1,2) = w_yz.
  const double sxx = s[XX], syy = s[YY], szz = s[ZZ], syz = s[YZ], sxz = s[XZ], sxy = s[XY];
  // (W S - S W)_ij = sum_k W_ik S_kj - S_ik W_kj ; with W antisymmetric this is W S + (W S)^T.
  // (W S)_xx = W_xy S_yx + W_xz S_zx
  const double ws_xx = w_xy * sxy + w_xz * sxz;
  const double ws_yy = -w_xy * sxy + w_yz * syz;
  const double ws_zz = -w_xz * sxz - w_yz * syz;
  // Off-diagonals of W S + (W S)^T: (WS)_ij + (WS)_ji
  // (W S)_yz = W_yx S_xz + W_yz S_zz = -w_xy sxz + w_yz szz
  // (W S)_zy = W_zx S_xy + W_zy S_yy = -w_xz sxy - w_yz syy
  const double r_yz = (-w_xy * sxz + w_yz * szz) + (-w_xz * sxy - w_yz * syy);
  // (W S)_xz = W_xy S_yz + W_xz S_zz ; (W S)_zx = W_zx S_xx + W_zy S_yx = -w_xz sxx - w_yz sxy
  const double r_xz = (w_xy * syz + w_xz * szz) + (-w_xz * sxx - w_yz * sxy);
  // (W S)_xy = W_xy S_yy + W_xz S_zy ; (W S)_yx = W_yx S_xx + W_yz S_zx = -w_xy sxx + w_yz sxz
  const double r_xy = (w_xy * syy + w_xz * syz) + (-w_xy * sxx + w_yz * sxz);
  s[XX] += 2.0 * ws_xx;
  s[YY] += 2.0 * ws_yy;
  s[ZZ] += 2.0 * ws_zz;
  s[YZ] += r_yz;
  s[XZ] += r_xz;
  s[XY] += r_xy;
}

/// Rotational part of the Jaumann stress update, integrated with the Hughes–Winget (1980)
/// rotation R = (I - dW/2)^-1 (I + dW/2) = I + 2 (A + A^2) / (1 + |a|^2), A = dW/2 with axial
/// vector a; then s <- R s R^T. R is exactly orthogonal, so I1, J2, J3 are kept to round-off for
/// any spin (incrementally objective), and it equals talus::jaumann_rotate to first order in dW.
/// jaumann_rotate (s += dW s - s dW, forward Euler) is not orthogonal: each step multiplies the
/// in-plane part of J2 by 1 + 4 w^2, which on the yield surface turns into spurious plastic flow
/// (and dilation) under pure rotation. Rotate the stress and the back stress with the SAME
/// function; rotate_state() uses this one. Spin (w_yz, w_xz, w_xy) as in core/types.hpp.
/// Written out (45 multiply-adds, no temporaries): it runs once per particle per step and was 17%
/// of an elastic step as Eigen 3x3 products. The arithmetic is rotate_objectively_values below, on
/// six components of any arithmetic type T (double, or a vector of doubles in the kernels of
/// solver/material_kernels.cpp): one expression for every path, so the scalar and the vector
/// updates agree bit for bit. T needs + - * / and T(double).
template <class T>
[[gnu::always_inline]] inline void rotate_objectively_values(T s[6], T w_yz, T w_xz, T w_xy) {
  // A = dW/2 with A(0,1) = w_xy/2, A(0,2) = w_xz/2, A(1,2) = w_yz/2; A^2 is symmetric:
  // (A^2)_00 = -(axy^2 + axz^2), (A^2)_01 = -axz ayz, (A^2)_02 = axy ayz, (A^2)_12 = -axy axz, ...
  const T axy = T(0.5) * w_xy, axz = T(0.5) * w_xz, ayz = T(0.5) * w_yz;
  const T c = T(2.0) / (T(1.0) + axy * axy + axz * axz + ayz * ayz);  // 2 / (1 + |a|^2)
  // R = I + c (A + A^2)
  const T r00 = T(1.0) - c * (axy * axy + axz * axz), r11 = T(1.0) - c * (axy * axy + ayz * ayz),
          r22 = T(1.0) - c * (axz * axz + ayz * ayz);
  const T r01 = c * (axy - axz * ayz), r10 = c * (-axy - axz * ayz);
  const T r02 = c * (axz + axy * ayz), r20 = c * (-axz + axy * ayz);
  const T r12 = c * (ayz - axy * axz), r21 = c * (-ayz - axy * axz);
  const T sxx = s[XX], syy = s[YY], szz = s[ZZ], syz = s[YZ], sxz = s[XZ], sxy = s[XY];
  // T = R S
  const T t00 = r00 * sxx + r01 * sxy + r02 * sxz, t01 = r00 * sxy + r01 * syy + r02 * syz,
          t02 = r00 * sxz + r01 * syz + r02 * szz;
  const T t10 = r10 * sxx + r11 * sxy + r12 * sxz, t11 = r10 * sxy + r11 * syy + r12 * syz,
          t12 = r10 * sxz + r11 * syz + r12 * szz;
  const T t20 = r20 * sxx + r21 * sxy + r22 * sxz, t21 = r20 * sxy + r21 * syy + r22 * syz,
          t22 = r20 * sxz + r21 * syz + r22 * szz;
  // S' = T R^T (symmetric: the six upper entries)
  s[XX] = t00 * r00 + t01 * r01 + t02 * r02;
  s[YY] = t10 * r10 + t11 * r11 + t12 * r12;
  s[ZZ] = t20 * r20 + t21 * r21 + t22 * r22;
  s[YZ] = t10 * r20 + t11 * r21 + t12 * r22;
  s[XZ] = t00 * r20 + t01 * r21 + t02 * r22;
  s[XY] = t00 * r10 + t01 * r11 + t02 * r12;
}

inline void rotate_objectively(Sym6& s, double w_yz, double w_xz, double w_xy) {
  double v[6];
  for (int c = 0; c < 6; ++c) v[c] = s[c];
  rotate_objectively_values(v, w_yz, w_xz, w_xy);
  for (int c = 0; c < 6; ++c) s[c] = v[c];
}

}  // namespace talus
