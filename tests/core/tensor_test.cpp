// Voigt tensor helpers (core/tensor.hpp): invariants, the matrix round trip, and the objective
// (Hughes & Winget 1980) rotation against the first-order Jaumann update.
#include "talus/core/tensor.hpp"

#include <gtest/gtest.h>

#include <cmath>

namespace talus {
namespace tensor_test {
namespace {

const Sym6 kStress{-3.0, -1.0, -2.0, 0.4, -0.7, 1.1};

TEST(Tensor, TraceDeviatorAndContraction) {
  EXPECT_DOUBLE_EQ(trace(kStress), -6.0);
  EXPECT_NEAR(trace(deviator(kStress)), 0.0, 1e-15);
  EXPECT_DOUBLE_EQ(double_contract(identity6(), identity6()), 3.0);
  // J2 = s:s / 2 of the deviator, shear terms counted twice in the full tensor.
  const Sym6 s = deviator(kStress);
  const double ss = s[0] * s[0] + s[1] * s[1] + s[2] * s[2] + 2 * (s[3] * s[3] + s[4] * s[4] + s[5] * s[5]);
  EXPECT_NEAR(j2(kStress), 0.5 * ss, 1e-14);
}

TEST(Tensor, MatrixRoundTrip) {
  const Mat3 m = to_matrix(kStress);
  EXPECT_EQ(m(1, 2), kStress[3]);
  EXPECT_EQ(m(2, 1), kStress[3]);
  EXPECT_EQ(m(0, 1), kStress[5]);
  const Sym6 back = from_matrix(m);
  for (int c = 0; c < 6; ++c) EXPECT_EQ(back[c], kStress[c]);
}

TEST(Tensor, ObjectiveRotationKeepsTheInvariantsAndIsJaumannToFirstOrder) {
  // A large spin: exactly orthogonal, so trace and J2 are kept to round-off.
  Sym6 big = kStress;
  rotate_objectively(big, 0.8, -0.5, 0.3);
  EXPECT_NEAR(trace(big), trace(kStress), 1e-13);
  EXPECT_NEAR(j2(big), j2(kStress), 1e-13);
  // A small spin w: the same as sigma + dW sigma - sigma dW up to O(w^2).
  for (const double w : {1e-3, 1e-4}) {
    Sym6 a = kStress, b = kStress;
    rotate_objectively(a, w, -2 * w, 3 * w);
    jaumann_rotate(b, w, -2 * w, 3 * w);
    double diff = 0.0;
    for (int c = 0; c < 6; ++c) diff = std::max(diff, std::abs(a[c] - b[c]));
    EXPECT_LT(diff, 50.0 * w * w) << w;
    EXPECT_GT(std::abs(a[5] - kStress[5]), 0.1 * w);  // and it did rotate
  }
}

}  // namespace
}  // namespace tensor_test
}  // namespace talus
