// Partition of unity and gradient consistency of the shape functions, through the same Stencil the
// transfers use (3D tensor product, seed 000 eq. 32).
#include "talus/grid/grid.hpp"
#include "talus/shape/linear.hpp"
#include "talus/transfer/stencil.hpp"

#include <gtest/gtest.h>

#include <random>

namespace talus {
namespace {

template <class Shape>
void check_consistency() {
  GridGeometry g;
  g.origin = Vec3(-1.0, 2.0, 0.5);
  g.h = 0.3;
  g.cells = {10, 10, 10};
  Grid grid(g);
  std::mt19937 rng(7);
  std::uniform_real_distribution<double> u(0.0, 3.0);
  Stencil<Shape> s;
  for (int trial = 0; trial < 200; ++trial) {
    const Vec3 x = g.origin + Vec3(u(rng), u(rng), u(rng));
    s.evaluate(grid, FlatTerrain{}, x[0], x[1], x[2], 0.25);
    double sum = 0.0;
    Vec3 grad_sum = Vec3::Zero();
    Vec3 position = Vec3::Zero();  // sum N_i x_i must reproduce x
    Mat3 grad_x = Mat3::Zero();    // sum x_i (x) grad N_i must be the identity
    constexpr int N = Shape::kNodes;
    int base[3];
    for (int d = 0; d < 3; ++d) base[d] = static_cast<int>(std::floor(g.to_grid(d, x[d])));
    double w1[N], dw1[N];
    for (int d = 0; d < 3; ++d) Shape::weights(g.to_grid(d, x[d]), 0.25, base[d], w1, dw1);
    for (int a = 0; a < N; ++a)
      for (int b = 0; b < N; ++b)
        for (int c = 0; c < N; ++c) {
          const double w = s.wx[a] * s.wy[b] * s.wz[c];
          Vec3 grad;
          s.gradient(a, b, c, grad[0], grad[1], grad[2]);
          const Vec3 xi(g.node_position(0, base[0] + a), g.node_position(1, base[1] + b), g.node_position(2, base[2] + c));
          sum += w;
          grad_sum += grad;
          position += w * xi;
          grad_x += xi * grad.transpose();
        }
    EXPECT_NEAR(sum, 1.0, 1e-14);
    EXPECT_NEAR(grad_sum.norm(), 0.0, 1e-12);
    EXPECT_NEAR((position - x).norm(), 0.0, 1e-13);
    EXPECT_NEAR((grad_x - Mat3::Identity()).norm(), 0.0, 1e-12);
  }
}

TEST(ShapeFunctions, LinearPartitionOfUnityAndLinearCompleteness) { check_consistency<LinearShape>(); }

TEST(ShapeFunctions, LinearWeightsAreHatFunctions) {
  int base;
  double w[2], dw[2];
  LinearShape::weights(3.25, 0.0, base, w, dw);  // seed 000 eq. 28: N = 1 - |x - x_i| / L
  EXPECT_EQ(base, 3);
  EXPECT_DOUBLE_EQ(w[0], 0.75);
  EXPECT_DOUBLE_EQ(w[1], 0.25);
  EXPECT_DOUBLE_EQ(dw[0], -1.0);
  EXPECT_DOUBLE_EQ(dw[1], 1.0);
}

}  // namespace
}  // namespace talus
