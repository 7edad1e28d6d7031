// Partition of unity, gradient consistency and linear completeness of every shape function,
// through the same Stencil the transfers use (3D tensor product, Edo & Matsubara 2015, eq. 32), and the 1D
// weights against their closed forms (linear eq. 28-29, GIMP eq. 30-31, quadratic B-spline).
#include "talus/grid/grid.hpp"
#include "talus/shape/bspline.hpp"
#include "talus/shape/gimp.hpp"
#include "talus/shape/linear.hpp"
#include "talus/transfer/stencil.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <random>
#include <type_traits>

namespace talus {
namespace shape_function_test {
namespace {

/// The small grid the stencil checks run on (off-origin, non-unit spacing).
GridGeometry test_geometry() {
  GridGeometry g;
  g.origin = Vec3(-1.0, 2.0, 0.5);
  g.h = 0.3;
  g.cells = {10, 10, 10};
  return g;
}

template <class Shape>
void check_consistency(const double half_width[3]) {
  const GridGeometry g = test_geometry();
  Grid grid(g);
  std::mt19937 rng(7);
  std::uniform_real_distribution<double> u(0.0, 3.0);
  Stencil<Shape> s;
  for (int trial = 0; trial < 200; ++trial) {
    const Vec3 x = g.origin + Vec3(u(rng), u(rng), u(rng));
    s.evaluate(grid, FlatTerrain{}, x[0], x[1], x[2], half_width);
    double sum = 0.0;
    Vec3 grad_sum = Vec3::Zero();
    Vec3 position = Vec3::Zero();  // sum N_i x_i must reproduce x
    Mat3 grad_x = Mat3::Zero();    // sum x_i (x) grad N_i must be the identity
    constexpr int N = Shape::kNodes;
    int base[3];
    double w1[N], dw1[N];
    for (int d = 0; d < 3; ++d) {
      Shape::weights(g.to_grid(d, x[d]), half_width[d], base[d], w1, dw1);
      // The support stays within the reach the colour blocks were sized for (cell_sort.hpp).
      const int cell = static_cast<int>(std::floor(g.to_grid(d, x[d])));
      EXPECT_GE(base[d], cell - Shape::kReachLow);
      EXPECT_LE(base[d] + N - 1, cell + Shape::kReachHigh);
    }
    for (int a = 0; a < N; ++a)
      for (int b = 0; b < N; ++b)
        for (int c = 0; c < N; ++c) {
          const double w = s.wx[a] * s.wy[b] * s.wz[c];
          EXPECT_GE(w, -1e-15);
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

template <class Shape>
void check_consistency(double half_width) {
  const double hw[3] = {half_width, half_width, half_width};
  check_consistency<Shape>(hw);
}

/// The derivative the shape returns matches a central difference of its weights.
template <class Shape>
void check_derivative(double half_width) {
  std::mt19937 rng(11);
  std::uniform_real_distribution<double> u(3.0, 6.0);
  constexpr int N = Shape::kNodes;
  for (int trial = 0; trial < 200; ++trial) {
    const double xi = u(rng), eps = 1e-6;
    int base, bp, bm;
    double w[N], dw[N], wp[N], wm[N], scratch[N];
    Shape::weights(xi, half_width, base, w, dw);
    Shape::weights(xi + eps, half_width, bp, wp, scratch);
    Shape::weights(xi - eps, half_width, bm, wm, scratch);
    if (bp != base || bm != base) continue;  // the stencil shifted between the three points
    for (int a = 0; a < N; ++a) EXPECT_NEAR(dw[a], (wp[a] - wm[a]) / (2 * eps), 2e-5) << "xi " << xi << " node " << a;
  }
}

TEST(ShapeFunctions, LinearPartitionOfUnityAndLinearCompleteness) { check_consistency<LinearShape>(0.25); }

TEST(ShapeFunctions, UGimpPartitionOfUnityAndLinearCompleteness) {
  for (double lp : {0.0, 0.125, 0.25, 0.5}) check_consistency<UGimpShape>(lp);
  for (double lp : {0.125, 0.25, 0.5}) check_derivative<UGimpShape>(lp);
}

// cpGIMP domains stretch: per-axis half widths, up to a domain two cells wide spread over three
// cells, and beyond (clamped to one cell).
TEST(ShapeFunctions, CpGimpPartitionOfUnityAndLinearCompletenessForStretchedDomains) {
  for (double lp : {0.05, 0.25, 0.5, 0.8, 1.0, 2.5}) check_consistency<CpGimpShape>(lp);
  for (double lp : {0.0, 0.05, 0.25, 0.5}) check_consistency<CpGimpNarrowShape>(lp);
  const double anisotropic[3] = {0.9, 0.2, 0.45};
  check_consistency<CpGimpShape>(anisotropic);
  for (double lp : {0.25, 0.7, 1.0}) check_derivative<CpGimpShape>(lp);
}

TEST(ShapeFunctions, QuadraticBSplinePartitionOfUnityAndLinearCompleteness) {
  check_consistency<QuadraticBSplineShape>(0.0);
  check_derivative<QuadraticBSplineShape>(0.0);
}

TEST(ShapeFunctions, LinearWeightsAreHatFunctions) {
  int base;
  double w[2], dw[2];
  LinearShape::weights(3.25, 0.0, base, w, dw);  // Edo & Matsubara 2015, eq. 28: N = 1 - |x - x_i| / L
  EXPECT_EQ(base, 3);
  EXPECT_DOUBLE_EQ(w[0], 0.75);
  EXPECT_DOUBLE_EQ(w[1], 0.25);
  EXPECT_DOUBLE_EQ(dw[0], -1.0);
  EXPECT_DOUBLE_EQ(dw[1], 1.0);
}

// Edo & Matsubara 2015, eq. 30-31 with L = 1, r = x_p - x_i:
//   |r| < lp:              S = 1 - (r^2 + lp^2) / (2 lp),   dS = -r / lp
//   lp <= |r| <= 1 - lp:   S = 1 - |r|,                     dS = -sign(r)
//   1 - lp < |r| < 1 + lp: S = (1 + lp - |r|)^2 / (4 lp),   dS = -sign(r) (1 + lp - |r|) / (2 lp)
double gimp_closed_form(double r, double lp, double& ds) {
  const double a = std::abs(r), sg = r > 0 ? 1.0 : -1.0;
  if (a < lp) {
    ds = -r / lp;
    return 1.0 - (r * r + lp * lp) / (2 * lp);
  }
  if (a <= 1.0 - lp) {
    ds = -sg;
    return 1.0 - a;
  }
  if (a < 1.0 + lp) {
    ds = -sg * (1.0 + lp - a) / (2 * lp);
    return (1.0 + lp - a) * (1.0 + lp - a) / (4 * lp);
  }
  ds = 0.0;
  return 0.0;
}

template <class Shape>
void check_gimp_closed_form(double lp) {
  for (double xi : {4.0, 4.1, 4.25, 4.3, 4.5, 4.62, 4.75, 4.9, 4.999}) {
    int base;
    double w[Shape::kNodes], dw[Shape::kNodes];
    Shape::weights(xi, lp, base, w, dw);
    double total = 0.0;
    for (int a = 0; a < Shape::kNodes; ++a) {
      double ds;
      const double s = gimp_closed_form(xi - (base + a), lp, ds);
      EXPECT_NEAR(w[a], s, 1e-14) << Shape::kName << " xi " << xi << " lp " << lp << " node " << base + a;
      EXPECT_NEAR(dw[a], ds, 1e-13) << Shape::kName << " xi " << xi << " lp " << lp << " node " << base + a;
      total += s;
    }
    EXPECT_NEAR(total, 1.0, 1e-14);  // the stencil holds the whole support
  }
}

TEST(ShapeFunctions, GimpWeightsMatchTheClosedFormOfEdoMatsubara2015Eq30And31) {
  for (double lp : {0.125, 0.25, 0.5}) {
    check_gimp_closed_form<UGimpShape>(lp);
    check_gimp_closed_form<CpGimpShape>(lp);
    check_gimp_closed_form<CpGimpNarrowShape>(lp);
  }
  // A domain wider than a cell (cpGIMP under stretch): the average of the hat over [x - lp, x + lp]
  // by quadrature.
  const double lp = 0.85, xi = 4.3;
  int base;
  double w[4], dw[4];
  CpGimpShape::weights(xi, lp, base, w, dw);
  for (int a = 0; a < 4; ++a) {
    double integral = 0.0;
    const int n = 200000;
    for (int k = 0; k < n; ++k) {
      const double x = xi - lp + (k + 0.5) * 2 * lp / n;
      integral += std::max(0.0, 1.0 - std::abs(x - (base + a)));
    }
    EXPECT_NEAR(w[a], integral / n, 1e-9);
  }
}

// The transfers evaluate cpGIMP on 3 nodes per axis where the domain fits (ParticleStencil): the
// weighted sums over the nodes must equal those of the 4-node stencil to round-off, and wider
// domains must take the 4-node one.
TEST(ShapeFunctions, NarrowCpGimpStencilGivesTheSameSumsAsTheFullOne) {
  const GridGeometry g = test_geometry();
  Grid grid(g);
  std::mt19937 rng(11);
  std::uniform_real_distribution<double> u(0.0, 3.0), width(0.0, 0.5);
  // A node field to sum, distinct per node: f(n) = sin(n).
  auto weighted_sums = [](const auto& s, double out[4]) {
    constexpr int N = std::decay_t<decltype(s)>::N;
    for (int k = 0; k < 4; ++k) out[k] = 0.0;
    for (int a = 0; a < N; ++a)
      for (int b = 0; b < N; ++b)
        for (int c = 0; c < N; ++c) {
          const double f = std::sin(static_cast<double>(s.ix[a] + s.iy[b] + s.iz[c]));
          double grad[3];
          s.gradient(a, b, c, grad[0], grad[1], grad[2]);
          out[0] += f * s.wx[a] * s.wy[b] * s.wz[c];
          for (int d = 0; d < 3; ++d) out[1 + d] += f * grad[d];
        }
    return N;
  };
  for (int trial = 0; trial < 500; ++trial) {
    const Vec3 x = g.origin + Vec3(u(rng), u(rng), u(rng));
    double hw[3] = {width(rng), width(rng), width(rng)};
    if (trial % 5 == 0) hw[trial % 3] = trial % 2 ? 0.5 : 0.0;  // the edges of the narrow range
    Stencil<CpGimpShape> full;
    full.evaluate(grid, FlatTerrain{}, x[0], x[1], x[2], hw);
    double expected[4], got[4];
    weighted_sums(full, expected);
    ParticleStencil<CpGimpShape> stencil;
    int nodes = 0;
    stencil.visit(grid, FlatTerrain{}, x[0], x[1], x[2], hw, [&](const auto& s) { nodes = weighted_sums(s, got); });
    EXPECT_EQ(nodes, 3);
    // round-off of sums of O(1) terms; the gradients carry 1/h
    for (int k = 0; k < 4; ++k)
      EXPECT_NEAR(got[k], expected[k], 1e-13 * (1.0 + std::abs(expected[k])) * (k == 0 ? 1.0 : 1.0 / g.h))
          << "trial " << trial << " sum " << k;
  }
  const double wide[3] = {0.2, 0.51, 0.3};
  ParticleStencil<CpGimpShape> stencil;
  int nodes = 0;
  double unused[4];
  stencil.visit(grid, FlatTerrain{}, 0.3, 3.1, 1.2, wide, [&](const auto& s) { nodes = weighted_sums(s, unused); });
  EXPECT_EQ(nodes, 4);
}

// The sort's cell (GridGeometry::cell_of) is the cell the linear stencil starts from, to the last
// bit: the sort computed (x - origin) / h and the stencil (x - origin) * (1/h), which round apart
// within an ulp of some faces (z = 0.22999999999999998 at h = 0.01: cell 24 and stencil 25), so a
// particle the sort placed at its block's slack edge scattered to a node past the block's range.
// Positions within 4 ulps of every face of 2000 cells, at cell sizes that showed it.
TEST(ShapeFunctions, TheSortsCellIsTheCellTheLinearStencilStartsFrom) {
  int all_divided_apart = 0;
  for (double h : {0.01, 0.003, 0.0125, 0.005, 0.025, 0.07}) {
    GridGeometry g;
    g.origin = Vec3(-0.3, 0.0, 0.1);
    g.h = h;
    g.cells = {2000, 2000, 2000};
    Grid grid(g);
    const double hw[3] = {0.0, 0.0, 0.0};
    Stencil<LinearShape> s;
    int checked = 0, divided_apart = 0;
    for (int k = 1; k < 2000; ++k)
      for (int d = 0; d < 3; ++d) {
        double x = g.origin[d] + k * h;
        for (int i = 0; i < 4; ++i) x = std::nextafter(x, -INFINITY);
        for (int ulp = -4; ulp <= 4; ++ulp, x = std::nextafter(x, INFINITY)) {
          double p[3] = {g.origin[0] + 1.0, g.origin[1] + 1.0, g.origin[2] + 1.0};
          p[d] = x;
          s.evaluate(grid, FlatTerrain{}, p[0], p[1], p[2], hw);
          ASSERT_EQ(g.cell_of(d, x), s.first[d]) << "h = " << h << ", x = " << x;
          ++checked;
          // the sort's former quotient: these positions do tell the two apart
          divided_apart += static_cast<int>(std::floor((x - g.origin[d]) / h + kPad)) != s.first[d];
        }
      }
    EXPECT_EQ(checked, 1999 * 3 * 9);
    all_divided_apart += divided_apart;
  }
  EXPECT_GT(all_divided_apart, 0);
}

TEST(ShapeFunctions, QuadraticBSplineWeightsMatchTheClosedForm) {
  // Nearest node i = 4 at u = x - x_i = 0.3: N_3 = (0.5 - u)^2 / 2, N_4 = 0.75 - u^2, N_5 = (0.5 + u)^2 / 2.
  int base;
  double w[3], dw[3];
  QuadraticBSplineShape::weights(4.3, 0.0, base, w, dw);
  EXPECT_EQ(base, 3);
  EXPECT_NEAR(w[0], 0.02, 1e-15);
  EXPECT_NEAR(w[1], 0.66, 1e-15);
  EXPECT_NEAR(w[2], 0.32, 1e-15);
  EXPECT_NEAR(dw[0], -0.2, 1e-15);
  EXPECT_NEAR(dw[1], -0.6, 1e-15);
  EXPECT_NEAR(dw[2], 0.8, 1e-15);
  // Below the midpoint the stencil starts one node lower: x = 4.7 is nearest node 5, u = -0.3.
  QuadraticBSplineShape::weights(4.7, 0.0, base, w, dw);
  EXPECT_EQ(base, 4);
  EXPECT_NEAR(w[0], 0.32, 1e-15);
  EXPECT_NEAR(w[1], 0.66, 1e-15);
  EXPECT_NEAR(w[2], 0.02, 1e-15);
}

}  // namespace
}  // namespace shape_function_test
}  // namespace talus
