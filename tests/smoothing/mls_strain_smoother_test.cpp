// MlsStrainSmoother (Edo & Matsubara 2015, eq. 38-46): the weight, exactness for polynomial fields, the guard,
// the body mask, agreement with a brute-force evaluation of eq. 42-46, and determinism.
#include "talus/smoothing/mls_strain_smoother.hpp"

#include "mls_cloud.hpp"

#include "talus/core/simd_dispatch.hpp"

#include <Eigen/Dense>
#include <gtest/gtest.h>
#include <omp.h>

#include <algorithm>
#include <cmath>
#include <cstring>
#include <functional>
#include <random>

namespace talus {
namespace mls_strain_smoother_test {
namespace {

using namespace mls_test;

TEST(MlsWeight, CubicSplineOfEdoMatsubara2015Eq39) {
  EXPECT_DOUBLE_EQ(mls_weight(0.0), 2.0 / 3.0);
  EXPECT_DOUBLE_EQ(mls_weight(0.5), 1.0 / 6.0);
  EXPECT_NEAR(mls_weight(0.5 - 1e-12), 1.0 / 6.0, 1e-11);  // continuous at s = 1/2
  const double e = 1e-6;  // continuous slope at s = 1/2: -1 from both sides
  EXPECT_NEAR((mls_weight(0.5) - mls_weight(0.5 - e)) / e, -1.0, 1e-5);
  EXPECT_NEAR((mls_weight(0.5 + e) - mls_weight(0.5)) / e, -1.0, 1e-5);
  EXPECT_NEAR(mls_weight(1.0 - 1e-9), 0.0, 1e-20);
  EXPECT_EQ(mls_weight(1.0), 0.0);
  EXPECT_EQ(mls_weight(1.5), 0.0);
  for (double s = 0.0; s < 1.0; s += 0.01) EXPECT_GT(mls_weight(s), 0.0) << s;
}

TEST(MlsBasis, TermCountsAndOrder) {
  EXPECT_EQ(mls_term_count(1, 3), 4);
  EXPECT_EQ(mls_term_count(2, 3), 10);
  EXPECT_EQ(mls_term_count(3, 3), 20);
  EXPECT_EQ(mls_term_count(3, 1), 4);
  EXPECT_EQ(mls_term_count(2, 2), 6);
  const double u[3] = {2.0, 3.0, 5.0};
  double F[20];
  mls_basis<3, 3>(u, F);
  const double expect[20] = {1, 2, 3, 5, 4, 6, 10, 9, 15, 25, 8, 12, 20, 18, 30, 50, 27, 45, 75, 125};
  for (int t = 0; t < 20; ++t) EXPECT_EQ(F[t], expect[t]) << t;
}

/// Smooth the cloud's field with `basis` (radius 2 cells, 2.5 for the cubic).
MlsCounts smooth_field(Cloud& c, MlsBasis basis) {
  MlsSettings s;
  s.basis = basis;
  s.radius_factor = basis == MlsBasis::Cubic ? 2.5 : 2.0;
  return MlsStrainSmoother(s, 1.0).smooth(c.particles, c.sort, c.geometry, c.inputs(), c.outputs(), {1});
}

// Exactness: an MLS fit with a complete polynomial basis reproduces every field in its span.
TEST(MlsStrainSmoother, LinearFieldReproducedByEveryBasis) {
  Cloud c = box_cloud(12, 0.3);
  c.set_field(linear_field);
  for (MlsBasis basis : {MlsBasis::Linear, MlsBasis::Quadratic, MlsBasis::Cubic}) {
    const MlsCounts n = smooth_field(c, basis);
    EXPECT_EQ(n.smoothed + n.unsmoothed, c.particles.size());
    EXPECT_EQ(n.unsmoothed, 0u) << to_string(basis);
    const double worst = worst_relative_change(c);
    std::printf("linear field, %s basis: max relative error %.3g\n", to_string(basis), worst);
    EXPECT_LT(worst, 1e-11) << to_string(basis);
  }
}

TEST(MlsStrainSmoother, QuadraticFieldReproducedByQuadraticAndCubicNotByLinear) {
  Cloud c = box_cloud(12, 0.3, 7);
  c.set_field(quadratic_field);
  for (MlsBasis basis : {MlsBasis::Linear, MlsBasis::Quadratic, MlsBasis::Cubic}) {
    const MlsCounts n = smooth_field(c, basis);
    EXPECT_EQ(n.unsmoothed, 0u) << to_string(basis);
    const double worst = worst_relative_change(c);
    std::printf("quadratic field, %s basis: max relative error %.3g\n", to_string(basis), worst);
    if (basis == MlsBasis::Linear)
      EXPECT_GT(worst, 1e-4);  // a linear fit cannot follow the curvature: the check can fail
    else
      EXPECT_LT(worst, 1e-11) << to_string(basis);
  }
}

// Direct evaluation of eq. 42-46 (A, B, Phi_I = F(x_p)^T (A^-1 B)_{:,I}) over all particle pairs,
// with absolute positions: the cell search must find exactly the neighbours within the radius.
/// The largest difference between the smoother's output in c.out (quadratic basis, 3D) and eq. 42-46
/// evaluated by brute force over every pair, over the particles clear of the guard; `compared`
/// counts them.
double worst_difference_from_brute_force(const Cloud& c, const MlsStrainSmoother& smoother, std::size_t& compared) {
  const auto& P = c.particles;
  const double h = smoother.radius();
  auto distance = [&](std::size_t p, std::size_t q) {
    return std::sqrt(std::pow(P.x[0][q] - P.x[0][p], 2) + std::pow(P.x[1][q] - P.x[1][p], 2) +
                     std::pow(P.x[2][q] - P.x[2][p], 2));
  };
  compared = 0;
  double worst = 0.0;
  for (std::size_t p = 0; p < P.size(); ++p) {
    std::vector<std::size_t> nb;
    for (std::size_t q = 0; q < P.size(); ++q)
      if (P.body[q] == P.body[p] && distance(p, q) < h) nb.push_back(q);
    auto F = [&](std::size_t q) {  // quadratic basis at absolute position / h
      Eigen::Matrix<double, 10, 1> f;
      double y[3] = {P.x[0][q] / h, P.x[1][q] / h, P.x[2][q] / h};
      mls_basis<2, 3>(y, f.data());
      return f;
    };
    Eigen::Matrix<double, 10, 10> A = Eigen::Matrix<double, 10, 10>::Zero();
    Eigen::MatrixXd B(10, nb.size());
    for (std::size_t I = 0; I < nb.size(); ++I) {
      const std::size_t q = nb[I];
      const double w = mls_weight(distance(p, q) / h);
      A += w * F(q) * F(q).transpose();  // eq. 42
      B.col(I) = w * F(q);               // eq. 43
    }
    Eigen::LLT<Eigen::Matrix<double, 10, 10>> llt(A);
    if (nb.size() < 10 || llt.info() != Eigen::Success || llt.rcond() < 1e-7) continue;  // stay clear of the guard
    const Eigen::RowVectorXd phi = F(p).transpose() * llt.solve(B);  // eq. 46
    EXPECT_NEAR(phi.sum(), 1.0, 1e-9);  // partition of unity (the constant is in the basis)
    for (int k = 0; k < 6; ++k) {
      double ref = 0.0;
      for (std::size_t I = 0; I < nb.size(); ++I) ref += phi[I] * c.in[k][nb[I]];  // eq. 45
      worst = std::max(worst, std::abs(c.out[k][p] - ref));
    }
    ++compared;
  }
  return worst;
}

TEST(MlsStrainSmoother, MatchesBruteForceEvaluationOfEq42To46) {
  Cloud c = two_body_cloud();  // two bodies that touch
  MlsSettings s;
  s.basis = MlsBasis::Quadratic;
  s.radius_factor = 1.7;
  const MlsStrainSmoother smoother(s, 1.0);
  const MlsCounts n = smoother.smooth(c.particles, c.sort, c.geometry, c.inputs(), c.outputs(), {1, 1});
  EXPECT_GT(n.smoothed, c.particles.size() / 2);
  std::size_t compared = 0;
  const double worst = worst_difference_from_brute_force(c, smoother, compared);
  std::printf("brute force: %zu particles compared, max difference %.3g\n", compared, worst);
  EXPECT_GT(compared, 250u);
  EXPECT_LT(worst, 1e-9);
}

// The solver re-sorts only once a particle may have moved a quarter of a cell: between sorts the
// search walks the cells within radius + drift. Every particle moved by up to `drift` after the
// sort, most into another cell: with that drift the result is still eq. 42-46 over every pair;
// with none (the sort taken as current) neighbours are missed; and a wider drift changes no bit
// (it only adds candidates of weight 0, in the same order).
TEST(MlsStrainSmoother, AStaleSortWithItsDriftFindsEveryNeighbour) {
  Cloud c;
  c.geometry.h = 1.0;
  c.geometry.cells = {10, 10, 10};
  add_lattice(c, {9, 8, 7}, 0.5, 0.45, Vec3(1.0, 1.3, 0.7), 0, 3);
  c.finish();
  c.set_random_inputs(12);
  const double drift = 0.8;  // cells: the solver re-sorts at 0.25; more makes misses certain without it
  std::mt19937 rng(5);
  std::normal_distribution<double> n01;
  std::size_t changed_cell = 0;
  for (std::size_t p = 0; p < c.particles.size(); ++p) {
    Vec3 d(n01(rng), n01(rng), n01(rng));
    d *= drift * std::uniform_real_distribution<double>(0.5, 1.0)(rng) / d.norm();
    bool moved_cell = false;
    for (int k = 0; k < 3; ++k) {
      const double x = c.particles.x[k][p];
      moved_cell = moved_cell || std::floor(x + d[k]) != std::floor(x);
      c.particles.x[k][p] = x + d[k];
    }
    changed_cell += moved_cell ? 1 : 0;
  }
  ASSERT_GT(changed_cell, c.particles.size() / 4);  // the sort is really stale
  MlsSettings s;
  s.basis = MlsBasis::Quadratic;
  s.radius_factor = 1.7;
  const MlsStrainSmoother smoother(s, 1.0);
  smoother.smooth(c.particles, c.sort, c.geometry, c.inputs(), c.outputs(), {1}, drift);
  const auto with_drift = c.out;
  std::size_t compared = 0;
  const double worst = worst_difference_from_brute_force(c, smoother, compared);
  EXPECT_GT(compared, 150u);
  EXPECT_LT(worst, 1e-9);
  smoother.smooth(c.particles, c.sort, c.geometry, c.inputs(), c.outputs(), {1}, 0.0);
  EXPECT_GT(worst_difference_from_brute_force(c, smoother, compared), 1e-6);
  smoother.smooth(c.particles, c.sort, c.geometry, c.inputs(), c.outputs(), {1}, 3 * drift);
  for (int k = 0; k < 6; ++k) EXPECT_EQ(std::memcmp(c.out[k].data(), with_drift[k].data(), 8 * c.out[k].size()), 0);
  EXPECT_THROW(smoother.smooth(c.particles, c.sort, c.geometry, c.inputs(), c.outputs(), {1}, -1.0),
               std::invalid_argument);
}

TEST(MlsStrainSmoother, GuardLeavesSparseOrDegenerateNeighbourhoodsAloneAndCountsThem) {
  // A lone particle and a pair: too few neighbours for 4 terms.
  Cloud c = sparse_cloud();
  const MlsStrainSmoother linear(MlsSettings{}, 1.0);
  MlsCounts n = linear.smooth(c.particles, c.sort, c.geometry, c.inputs(), c.outputs(), {1});
  EXPECT_EQ(n.unsmoothed, 3u);
  EXPECT_EQ(n.smoothed, 0u);
  for (int k = 0; k < 6; ++k) EXPECT_EQ(c.out[k], c.in[k]);

  // A slab two particle layers thick along z: enough neighbours, but z^2 is collinear with z and 1
  // on two z values, so a 3D quadratic A is singular; the guard must catch it. The same slab
  // fitted with a basis over (x, y) only is smoothed everywhere.
  Cloud slab;
  slab.geometry.h = 1.0;
  slab.geometry.cells = {10, 10, 3};
  add_lattice(slab, {14, 14, 2}, 0.5, 0.0, Vec3(1.0, 1.0, 1.0), 0, 5);
  slab.finish();
  slab.set_field(quadratic_field);
  MlsSettings s;
  s.basis = MlsBasis::Quadratic;
  n = MlsStrainSmoother(s, 1.0).smooth(slab.particles, slab.sort, slab.geometry, slab.inputs(), slab.outputs(), {1});
  EXPECT_EQ(n.unsmoothed, slab.particles.size());
  s.axes = {true, true, false};
  n = MlsStrainSmoother(s, 1.0).smooth(slab.particles, slab.sort, slab.geometry, slab.inputs(), slab.outputs(), {1});
  EXPECT_EQ(n.unsmoothed, 0u);
  EXPECT_EQ(n.smoothed, slab.particles.size());
}

TEST(MlsStrainSmoother, OnlySelectedBodiesAreSmoothedAndBodiesDoNotMix) {
  // Two touching bodies with different constant increments: a constant is in every basis, so each
  // body keeps its own value exactly only if the other body's particles are not its neighbours.
  Cloud c;
  c.geometry.h = 1.0;
  c.geometry.cells = {10, 6, 6};
  add_lattice(c, {8, 8, 8}, 0.5, 0.3, Vec3(1.0, 1.0, 1.0), 0, 1);
  add_lattice(c, {8, 8, 8}, 0.5, 0.3, Vec3(5.0, 1.0, 1.0), 1, 2);
  c.finish();
  for (std::size_t p = 0; p < c.particles.size(); ++p)
    for (int k = 0; k < 6; ++k) c.in[k][p] = c.particles.body[p] == 0 ? 1.0 + k : -3.0 * std::sin(double(p));
  const MlsStrainSmoother smoother(MlsSettings{}, 1.0);
  const MlsCounts n = smoother.smooth(c.particles, c.sort, c.geometry, c.inputs(), c.outputs(), {1, 0});
  EXPECT_EQ(n.smoothed + n.unsmoothed, 512u);  // only body 0 counts
  EXPECT_EQ(n.unsmoothed, 0u);
  for (std::size_t p = 0; p < c.particles.size(); ++p)
    for (int k = 0; k < 6; ++k) {
      if (c.particles.body[p] == 0)
        EXPECT_NEAR(c.out[k][p], 1.0 + k, 1e-12);
      else
        EXPECT_EQ(c.out[k][p], c.in[k][p]);  // not smoothed: copied bit for bit
    }
}

TEST(MlsStrainSmoother, GuardDecidesLikeEigensRcondAtAnyThreshold) {
  // The smoother decides well-conditioned fits from the exact condition number and leaves the rest
  // to Eigen's LLT and rcond(). Thresholds taken from the particles' own rcond values put many of
  // them just above and below the threshold, so both paths decide; each particle must be smoothed
  // exactly when the reference LLT + rcond() (Edo & Matsubara 2015, eq. 42, relative coordinates) accepts it.
  Cloud c = box_cloud(10, 0.45, 21);
  c.set_random_inputs(7);
  const auto& P = c.particles;
  const double h = 1.0;
  std::vector<double> rcond(P.size(), 0.0);  // 0: too few neighbours or not positive definite
  for (std::size_t p = 0; p < P.size(); ++p) {
    Eigen::Matrix4d A = Eigen::Matrix4d::Zero();
    int n = 0;
    for (std::size_t q = 0; q < P.size(); ++q) {
      const Eigen::Vector3d u((P.x[0][q] - P.x[0][p]) / h, (P.x[1][q] - P.x[1][p]) / h, (P.x[2][q] - P.x[2][p]) / h);
      if (u.norm() >= 1.0) continue;
      Eigen::Vector4d f;
      mls_basis<1, 3>(u.data(), f.data());
      A += mls_weight(u.norm()) * f * f.transpose();
      ++n;
    }
    const Eigen::LLT<Eigen::Matrix4d> llt(A);
    if (n >= 4 && llt.info() == Eigen::Success) rcond[p] = llt.rcond();
  }
  std::vector<double> sorted = rcond;
  std::sort(sorted.begin(), sorted.end());
  for (double quantile : {0.1, 0.5, 0.9}) {
    MlsSettings s;
    s.radius_factor = h;
    s.min_rcond = sorted[static_cast<std::size_t>(quantile * (sorted.size() - 1))] * (1.0 + 1e-9);
    const MlsCounts n = MlsStrainSmoother(s, 1.0).smooth(P, c.sort, c.geometry, c.inputs(), c.outputs(), {1});
    std::size_t expected_unsmoothed = 0, near = 0;
    for (std::size_t p = 0; p < P.size(); ++p) {
      const bool accept = rcond[p] >= s.min_rcond;
      expected_unsmoothed += accept ? 0 : 1;
      near += accept && rcond[p] < 2.0 * s.min_rcond ? 1 : 0;  // decided by Eigen's rcond()
      for (int k = 0; k < 6; ++k)  // kept bit for bit, or replaced by the fit of random values
        EXPECT_EQ(c.out[k][p] == c.in[k][p], !accept) << p;
    }
    EXPECT_GT(near, 0u) << quantile;
    EXPECT_EQ(n.unsmoothed, expected_unsmoothed) << quantile;
    EXPECT_EQ(n.smoothed + n.unsmoothed, P.size());
  }
}

TEST(MlsStrainSmoother, BitIdenticalForOneAndTwoThreads) {
  Cloud c = box_cloud(14, 0.45, 9);
  c.set_random_inputs(5);
  const int saved = omp_get_max_threads();
  for (MlsBasis basis : {MlsBasis::Linear, MlsBasis::Cubic}) {
    MlsSettings s;
    s.basis = basis;
    const MlsStrainSmoother smoother(s, 1.0);
    omp_set_num_threads(1);
    const MlsCounts n1 = smoother.smooth(c.particles, c.sort, c.geometry, c.inputs(), c.outputs(), {1});
    const auto one = c.out;
    omp_set_num_threads(2);
    const MlsCounts n2 = smoother.smooth(c.particles, c.sort, c.geometry, c.inputs(), c.outputs(), {1});
    EXPECT_EQ(n1.smoothed, n2.smoothed);
    EXPECT_EQ(n1.unsmoothed, n2.unsmoothed);
    for (int k = 0; k < 6; ++k) {
      ASSERT_EQ(one[k].size(), c.out[k].size());
      EXPECT_EQ(std::memcmp(one[k].data(), c.out[k].data(), one[k].size() * sizeof(double)), 0) << k;
      EXPECT_NE(one[k], c.in[k]);  // something was smoothed
    }
  }
  omp_set_num_threads(saved);
}

// The smoother runs on every instruction-set path (core/simd_dispatch.hpp) with the reference's bits:
// each basis, two bodies, a body that is not smoothed, particles with too few neighbours, and a
// NaN and an infinite input (a non-finite increment poisons its own neighbours and nobody else).
TEST(MlsStrainSmoother, EveryInstructionSetPathGivesTheReferenceBits) {
  Cloud c = three_body_cloud();
  c.set_random_inputs(13);
  c.in[2][17] = std::nan("");
  c.in[4][300] = HUGE_VAL;
  const std::vector<std::string> paths = available_isas();
  ASSERT_GE(paths.size(), 2u);
  for (MlsBasis basis : {MlsBasis::Linear, MlsBasis::Quadratic, MlsBasis::Cubic}) {
    MlsSettings s;
    s.basis = basis;
    s.radius_factor = basis == MlsBasis::Cubic ? 2.5 : 1.7;
    const MlsStrainSmoother smoother(s, 1.0);
    select_isa("reference");
    const MlsCounts n_ref = smoother.smooth(c.particles, c.sort, c.geometry, c.inputs(), c.outputs(), {1, 1, 0});
    const auto reference = c.out;
    EXPECT_GT(n_ref.smoothed, 0u);
    EXPECT_GT(n_ref.unsmoothed, 0u);
    // A non-finite result only in the poisoned component, and only within the radius of that input.
    for (auto [k, source] : {std::pair<int, std::size_t>{2, 17}, {4, 300}}) {
      std::size_t poisoned = 0;
      for (std::size_t p = 0; p < c.particles.size(); ++p) {
        if (std::isfinite(reference[k][p])) continue;
        ++poisoned;
        const double r = std::hypot(c.particles.x[0][p] - c.particles.x[0][source],
                                    c.particles.x[1][p] - c.particles.x[1][source],
                                    c.particles.x[2][p] - c.particles.x[2][source]);
        EXPECT_LT(r, smoother.radius()) << p;
      }
      EXPECT_GT(poisoned, 1u);
    }
    for (int k : {0, 1, 3, 5})
      for (double v : reference[k]) EXPECT_TRUE(std::isfinite(v));
    for (std::size_t i = 1; i < paths.size(); ++i) {
      select_isa(paths[i]);
      const MlsCounts n = smoother.smooth(c.particles, c.sort, c.geometry, c.inputs(), c.outputs(), {1, 1, 0});
      EXPECT_EQ(n.smoothed, n_ref.smoothed) << paths[i];
      EXPECT_EQ(n.unsmoothed, n_ref.unsmoothed) << paths[i];
      for (int k = 0; k < 6; ++k)
        EXPECT_EQ(std::memcmp(reference[k].data(), c.out[k].data(), reference[k].size() * sizeof(double)), 0)
            << paths[i] << " component " << k;
    }
    select_isa("auto");
  }
}

}  // namespace
}  // namespace mls_strain_smoother_test
}  // namespace talus
