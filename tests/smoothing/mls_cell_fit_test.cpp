// The one-fit-per-cell variant of the MLS smoother (MlsVariant::Cell): one fit per cell and body,
// centred at the cell's centre (Edo & Matsubara 2015, eq. 42-46 with the cell centre in place of the
// particle), evaluated at each of the cell's particles. Exactness for polynomial fields, agreement
// with a brute-force evaluation, the guard and the body mask, and the same bits for any thread
// count and on every instruction-set path.
#include "talus/smoothing/mls_strain_smoother.hpp"

#include "mls_cloud.hpp"

#include "talus/core/simd_dispatch.hpp"

#include <Eigen/Dense>
#include <gtest/gtest.h>
#include <omp.h>

#include <algorithm>
#include <cmath>
#include <cstring>
#include <map>
#include <tuple>

namespace talus {
namespace mls_cell_fit_test {
namespace {

using namespace mls_test;

MlsSettings cell_settings(MlsBasis basis, double radius_factor) {
  MlsSettings s;
  s.basis = basis;
  s.radius_factor = radius_factor;
  s.variant = MlsVariant::Cell;
  return s;
}

// A fit with a complete polynomial basis reproduces every field in its span, wherever it is centred.
TEST(MlsCellFit, PolynomialFieldsInTheBasisAreReproduced) {
  for (bool quadratic : {false, true}) {
    Cloud c = box_cloud(12, 0.3, quadratic ? 7 : 1);
    c.set_field(quadratic ? quadratic_field : linear_field);
    for (MlsBasis basis : {MlsBasis::Linear, MlsBasis::Quadratic, MlsBasis::Cubic}) {
      const MlsStrainSmoother smoother(cell_settings(basis, basis == MlsBasis::Cubic ? 2.5 : 2.0), 1.0);
      const MlsCounts n = smoother.smooth(c.particles, c.sort, c.geometry, c.inputs(), c.outputs(), {1});
      EXPECT_EQ(n.smoothed, c.particles.size()) << to_string(basis);
      EXPECT_EQ(n.unsmoothed, 0u);
      const double worst = worst_relative_change(c);
      std::printf("cell fit, %s field, %s basis: max relative error %.3g\n", quadratic ? "quadratic" : "linear",
                  to_string(basis), worst);
      if (quadratic && basis == MlsBasis::Linear)
        EXPECT_GT(worst, 1e-4);  // a linear fit cannot follow the curvature: the check can fail
      else
        EXPECT_LT(worst, 1e-11) << to_string(basis);
    }
  }
}

// Direct evaluation: for every cell and body, A and B over all particles of that body within the
// radius of the cell's centre (absolute coordinates), the coefficients A^-1 B, evaluated at each of
// the cell's particles. The cell search must find exactly the particles within the radius.
TEST(MlsCellFit, MatchesBruteForceEvaluationAtTheCellCentres) {
  Cloud c = two_body_cloud();  // two bodies that touch
  const MlsStrainSmoother smoother(cell_settings(MlsBasis::Quadratic, 1.7), 1.0);
  const MlsCounts n = smoother.smooth(c.particles, c.sort, c.geometry, c.inputs(), c.outputs(), {1, 1});
  EXPECT_GT(n.smoothed, c.particles.size() / 2);
  const auto& P = c.particles;
  const double h = smoother.radius();
  auto F = [&](const double* x) {  // quadratic basis at absolute position / h
    Eigen::Matrix<double, 10, 1> f;
    const double y[3] = {x[0] / h, x[1] / h, x[2] / h};
    mls_basis<2, 3>(y, f.data());
    return f;
  };
  // The cells and bodies present, each with its particles.
  std::map<std::tuple<int, int, int, int>, std::vector<std::size_t>> cells;
  for (std::size_t p = 0; p < P.size(); ++p)
    cells[{c.geometry.cell_of(0, P.x[0][p]), c.geometry.cell_of(1, P.x[1][p]), c.geometry.cell_of(2, P.x[2][p]),
           P.body[p]}]
        .push_back(p);
  std::size_t compared = 0;
  double worst = 0.0;
  for (const auto& [key, members] : cells) {
    const auto [i, j, k, body] = key;
    const double xc[3] = {c.geometry.node_position(0, i) + 0.5, c.geometry.node_position(1, j) + 0.5,
                          c.geometry.node_position(2, k) + 0.5};
    Eigen::Matrix<double, 10, 10> A = Eigen::Matrix<double, 10, 10>::Zero();
    Eigen::Matrix<double, 10, 6> B = Eigen::Matrix<double, 10, 6>::Zero();
    int neighbours = 0;
    for (std::size_t q = 0; q < P.size(); ++q) {
      const double r = std::hypot(P.x[0][q] - xc[0], P.x[1][q] - xc[1], P.x[2][q] - xc[2]);
      if (P.body[q] != body || r >= h) continue;
      const double x[3] = {P.x[0][q], P.x[1][q], P.x[2][q]};
      const double w = mls_weight(r / h);
      A += w * F(x) * F(x).transpose();  // eq. 42
      for (int e = 0; e < 6; ++e) B.col(e) += w * F(x) * c.in[e][q];
      ++neighbours;
    }
    const Eigen::LLT<Eigen::Matrix<double, 10, 10>> llt(A);
    if (neighbours < 10 || llt.info() != Eigen::Success || llt.rcond() < 1e-7) continue;  // clear of the guard
    const Eigen::Matrix<double, 10, 6> C = llt.solve(B);
    for (std::size_t p : members) {
      const double x[3] = {P.x[0][p], P.x[1][p], P.x[2][p]};
      const Eigen::Matrix<double, 1, 6> ref = F(x).transpose() * C;
      for (int e = 0; e < 6; ++e) worst = std::max(worst, std::abs(c.out[e][p] - ref[e]));
      ++compared;
    }
  }
  std::printf("cell fit, brute force: %zu particles compared, max difference %.3g\n", compared, worst);
  EXPECT_GT(compared, 250u);
  EXPECT_LT(worst, 1e-9);
}

TEST(MlsCellFit, GuardAndBodyMaskAsForTheParticleFit) {
  // Too few neighbours for 4 terms: kept and counted.
  Cloud sparse = sparse_cloud();
  const MlsStrainSmoother linear(cell_settings(MlsBasis::Linear, 2.0), 1.0);
  MlsCounts n = linear.smooth(sparse.particles, sparse.sort, sparse.geometry, sparse.inputs(), sparse.outputs(), {1});
  EXPECT_EQ(n.unsmoothed, 3u);
  EXPECT_EQ(n.smoothed, 0u);
  for (int k = 0; k < 6; ++k) EXPECT_EQ(sparse.out[k], sparse.in[k]);

  // Two touching bodies, the boundary between them inside cells, with different constant
  // increments: each body keeps its constant exactly only if the other's particles are not its
  // neighbours; an unselected body is copied bit for bit.
  for (const std::vector<std::uint8_t>& selected : {std::vector<std::uint8_t>{1, 0}, {1, 1}}) {
    Cloud c;
    c.geometry.h = 1.0;
    c.geometry.cells = {10, 6, 6};
    add_lattice(c, {8, 8, 8}, 0.5, 0.3, Vec3(1.0, 1.0, 1.0), 0, 1);
    add_lattice(c, {8, 8, 8}, 0.5, 0.3, Vec3(4.75, 1.0, 1.0), 1, 2);  // mixes with body 0 in the cells at x = 4..5
    c.finish();
    for (std::size_t p = 0; p < c.particles.size(); ++p)
      for (int k = 0; k < 6; ++k) c.in[k][p] = c.particles.body[p] == 0 ? 1.0 + k : -2.0 - k;
    n = linear.smooth(c.particles, c.sort, c.geometry, c.inputs(), c.outputs(), selected);
    EXPECT_EQ(n.smoothed + n.unsmoothed, selected[1] ? 1024u : 512u);
    EXPECT_EQ(n.unsmoothed, 0u);
    for (std::size_t p = 0; p < c.particles.size(); ++p)
      for (int k = 0; k < 6; ++k) {
        const int body = c.particles.body[p];
        if (selected[body])
          EXPECT_NEAR(c.out[k][p], body == 0 ? 1.0 + k : -2.0 - k, 1e-12) << p;
        else
          EXPECT_EQ(c.out[k][p], c.in[k][p]);
      }
  }
}

// Bit-identical results for 1 and 3 threads and on every instruction-set path: each basis, two
// bodies sharing cells, a body that is not smoothed, a lone particle (the guard), a 2D basis, and a
// NaN and an infinite input (a non-finite increment poisons the cells whose centre it is near).
TEST(MlsCellFit, SameBitsForAnyThreadCountAndOnEveryInstructionSetPath) {
  Cloud c = three_body_cloud(5.3);  // the first two bodies share cells
  c.set_random_inputs(13);
  c.in[2][17] = std::nan("");
  c.in[4][300] = HUGE_VAL;
  const std::vector<std::string> paths = available_isas();
  ASSERT_GE(paths.size(), 2u);
  const int saved = omp_get_max_threads();
  for (MlsBasis basis : {MlsBasis::Linear, MlsBasis::Quadratic, MlsBasis::Cubic}) {
    MlsSettings s = cell_settings(basis, basis == MlsBasis::Cubic ? 2.5 : 1.7);
    if (basis == MlsBasis::Quadratic) s.axes = {true, false, true};
    const MlsStrainSmoother smoother(s, 1.0);
    select_isa("reference");
    omp_set_num_threads(1);
    const MlsCounts n_ref = smoother.smooth(c.particles, c.sort, c.geometry, c.inputs(), c.outputs(), {1, 1, 0});
    const auto reference = c.out;
    EXPECT_GT(n_ref.smoothed, 0u);
    EXPECT_GT(n_ref.unsmoothed, 0u);
    for (int k : {0, 1, 3, 5})
      for (double v : reference[k]) EXPECT_TRUE(std::isfinite(v));
    std::size_t poisoned = 0;
    for (double v : reference[2]) poisoned += std::isfinite(v) ? 0 : 1;
    EXPECT_GT(poisoned, 1u);
    EXPECT_LT(poisoned, c.particles.size() / 4);
    omp_set_num_threads(3);
    for (const std::string& path : paths) {
      select_isa(path);
      const MlsCounts n = smoother.smooth(c.particles, c.sort, c.geometry, c.inputs(), c.outputs(), {1, 1, 0});
      EXPECT_EQ(n.smoothed, n_ref.smoothed) << path;
      EXPECT_EQ(n.unsmoothed, n_ref.unsmoothed) << path;
      for (int k = 0; k < 6; ++k)
        EXPECT_EQ(std::memcmp(reference[k].data(), c.out[k].data(), reference[k].size() * sizeof(double)), 0)
            << path << " component " << k << ", " << to_string(basis);
    }
    select_isa("auto");
  }
  omp_set_num_threads(saved);
}

// The cell fit is a different smoothing from the particle fit, but of the same field: on a smooth
// field with noise the two agree far better than either agrees with the noisy input.
TEST(MlsCellFit, CloseToTheParticleFitOnANoisySmoothField) {
  Cloud c = box_cloud(14, 0.4, 19);
  std::mt19937 rng(3);
  std::uniform_real_distribution<double> noise(-1.0, 1.0);
  for (std::size_t p = 0; p < c.particles.size(); ++p)
    for (int k = 0; k < 6; ++k) {
      const double x[3] = {c.particles.x[0][p], c.particles.x[1][p], c.particles.x[2][p]};
      c.in[k][p] = std::sin(0.6 * x[0] + 0.1 * k) * std::cos(0.4 * x[2]) + 0.2 * noise(rng);
    }
  MlsSettings particle;
  particle.radius_factor = 1.5;
  MlsStrainSmoother(particle, 1.0).smooth(c.particles, c.sort, c.geometry, c.inputs(), c.outputs(), {1});
  const auto by_particle = c.out;
  MlsStrainSmoother(cell_settings(MlsBasis::Linear, 1.5), 1.0)
      .smooth(c.particles, c.sort, c.geometry, c.inputs(), c.outputs(), {1});
  double between = 0.0, to_input = 0.0;
  for (int k = 0; k < 6; ++k)
    for (std::size_t p = 0; p < c.particles.size(); ++p) {
      between += std::pow(c.out[k][p] - by_particle[k][p], 2);
      to_input += std::pow(by_particle[k][p] - c.in[k][p], 2);
    }
  std::printf("cell fit against the particle fit: rms %.3g, particle fit against the input: rms %.3g\n",
              std::sqrt(between / (6.0 * c.particles.size())), std::sqrt(to_input / (6.0 * c.particles.size())));
  EXPECT_LT(between, 0.25 * to_input);
}

}  // namespace
}  // namespace mls_cell_fit_test
}  // namespace talus
