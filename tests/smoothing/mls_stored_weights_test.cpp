// The `reused` MLS variant's stored weights (smoothing/mls_stored_weights.hpp): applied to the
// inputs they were fitted with, and to any other inputs at the same positions, they give the
// particle fit's bits (Edo & Matsubara 2015, eq. 45-46), on every path and thread count; carried
// over a reordering of the store they follow the particles.
#include "talus/core/simd_dispatch.hpp"
#include "talus/smoothing/mls_stored_weights.hpp"

#include "mls_cloud.hpp"

#include <gtest/gtest.h>
#include <omp.h>

#include <array>
#include <cmath>
#include <cstring>
#include <numeric>
#include <string>

namespace talus {
namespace mls_stored_weights_test {
namespace {

using namespace mls_test;

bool same_bits(const std::vector<double>& a, const std::vector<double>& b) {
  return a.size() == b.size() && std::memcmp(a.data(), b.data(), a.size() * sizeof(double)) == 0;
}

TEST(MlsStoredWeights, ApplyGivesTheFitsBitsForAnyInputsPathAndThreadCount) {
  Cloud c = three_body_cloud();
  const std::vector<std::uint8_t> smoothed_bodies{1, 1, 0};
  std::vector<double> rows;
  // (at 3 cells the weights fill several segments on each thread: MlsStoredWeights::kSegmentEntries)
  for (auto [basis, radius] : {std::pair{MlsBasis::Linear, 1.7}, {MlsBasis::Quadratic, 3.0}}) {
    MlsSettings s;
    s.basis = basis;
    s.radius_factor = radius;
    const MlsStrainSmoother smoother(s, 1.0);
    c.set_random_inputs(7);
    MlsStoredWeights weights;
    omp_set_num_threads(2);
    const MlsCounts fitted = smoother.smooth(c.particles, c.sort, c.geometry, c.inputs(), c.outputs(), smoothed_bodies,
                                             0.0, nullptr, &weights);
    EXPECT_GT(fitted.smoothed, 0u);
    EXPECT_GT(fitted.unsmoothed, 0u);
    ASSERT_EQ(weights.particle_count(), c.particles.size());
    const auto fit_out = c.out;
    // Any inputs: the fit at the same positions and the stored weights agree bit for bit, with a
    // NaN and an infinity among them (each stays within its neighbours' results).
    for (unsigned seed : {7u, 8u}) {
      c.set_random_inputs(seed);
      c.in[2][17] = std::nan("");
      c.in[4][300] = HUGE_VAL;
      const MlsCounts reference = smoother.smooth(c.particles, c.sort, c.geometry, c.inputs(), c.outputs(), smoothed_bodies);
      const auto expected = c.out;
      if (seed == 7u) {
        for (int k : {0, 1, 3, 5}) EXPECT_TRUE(same_bits(expected[k], fit_out[k]));  // the fit's own pass
      }
      for (const std::string& path : available_isas())
        for (int threads : {1, 3}) {
          select_isa(path);
          omp_set_num_threads(threads);
          for (auto& o : c.out) std::fill(o.begin(), o.end(), -7.0);
          const MlsCounts applied = weights.apply(c.inputs(), c.outputs(), c.particles.body, smoothed_bodies, rows);
          EXPECT_EQ(applied.smoothed, reference.smoothed) << path;
          EXPECT_EQ(applied.unsmoothed, reference.unsmoothed) << path;
          for (int k = 0; k < 6; ++k)
            EXPECT_TRUE(same_bits(c.out[k], expected[k])) << path << ", " << threads << " threads, component " << k;
        }
      select_isa("auto");
      omp_set_num_threads(2);
    }
    // Entries are the neighbours within the radius and body: at most about 4/3 pi r^3 * 8 (8
    // particles per unit volume), fewer near the small bodies' faces.
    const double mean = double(weights.entry_count()) / double(fitted.smoothed), ball = 4.0 / 3.0 * M_PI * radius * radius * radius * 8.0;
    EXPECT_GT(mean, 0.3 * ball);
    EXPECT_LT(mean, ball);
    if (radius > 2.0) {
      EXPECT_GT(weights.entry_count(), 2 * MlsStoredWeights::kSegmentEntries);  // 2 threads: one had 2
    }
  }
}

/// The default linear fit of random inputs (seeded), every body smoothed, keeping its weights; its results.
std::array<std::vector<double>, 6> fit_keeping_weights(Cloud& c, unsigned seed, MlsStoredWeights& weights) {
  c.set_random_inputs(seed);
  MlsStrainSmoother(MlsSettings{}, 1.0)
      .smooth(c.particles, c.sort, c.geometry, c.inputs(), c.outputs(), {1, 1, 1}, 0.0, nullptr, &weights);
  return c.out;
}

TEST(MlsStoredWeights, RemapFollowsTheParticlesAndRefusesAMissingOne) {
  Cloud c = three_body_cloud();
  const std::vector<std::uint8_t> smoothed_bodies{1, 1, 1};
  MlsStoredWeights weights;
  const auto expected = fit_keeping_weights(c, 5, weights);
  // Reverse the store: the inputs follow their particles; so must the results.
  const std::size_t n = c.particles.size();
  std::vector<std::uint32_t> order(n);
  std::iota(order.rbegin(), order.rend(), 0u);
  const ParticleArray<std::int64_t> ids_before = c.particles.id;
  c.particles.permute(order);
  std::array<std::vector<double>, 6> in, out;
  std::array<const double*, 6> in_ptr;
  std::array<double*, 6> out_ptr;
  for (int k = 0; k < 6; ++k) {
    in[k].resize(n);
    out[k].assign(n, 0.0);
    for (std::size_t p = 0; p < n; ++p) in[k][p] = c.in[k][order[p]];
    in_ptr[k] = in[k].data();
    out_ptr[k] = out[k].data();
  }
  MlsStoredWeights carried = weights;
  ASSERT_TRUE(carried.remap(ids_before, c.particles.id));
  std::vector<double> rows;
  carried.apply(in_ptr, out_ptr, c.particles.body, smoothed_bodies, rows);
  for (int k = 0; k < 6; ++k)
    for (std::size_t p = 0; p < n; ++p) ASSERT_EQ(out[k][p], expected[k][order[p]]) << p;
  // A particle missing (one left through an open face), or an id twice: refused, and cleared.
  MlsStoredWeights missing = weights;
  EXPECT_FALSE(missing.remap(ids_before, std::span(c.particles.id).first(n - 1)));
  EXPECT_TRUE(missing.empty());
  MlsStoredWeights repeated = weights;
  ParticleArray<std::int64_t> twice = c.particles.id;
  twice[1] = twice[0];
  EXPECT_FALSE(repeated.remap(ids_before, twice));
  EXPECT_TRUE(repeated.empty());
}

TEST(MlsStoredWeights, FlattenedAndAssignedBackTheyApplyAlikeAndADamagedListIsRefused) {
  Cloud c = three_body_cloud();
  const std::vector<std::uint8_t> smoothed_bodies{1, 1, 1};
  MlsStoredWeights weights;
  const auto expected = fit_keeping_weights(c, 9, weights);
  std::vector<std::uint64_t> offsets;
  std::vector<std::uint32_t> neighbour;
  std::vector<double> phi;
  weights.flatten(offsets, neighbour, phi);
  EXPECT_EQ(offsets.back(), weights.entry_count());
  MlsStoredWeights back;
  EXPECT_TRUE(back.assign(offsets, neighbour, phi));
  std::vector<double> rows;
  back.apply(c.inputs(), c.outputs(), c.particles.body, smoothed_bodies, rows);
  for (int k = 0; k < 6; ++k) EXPECT_TRUE(same_bits(c.out[k], expected[k])) << k;
  // Lists that are not such a form are refused (a damaged checkpoint): a neighbour beyond the
  // particles, lengths that disagree.
  std::vector<std::uint32_t> beyond = neighbour;
  beyond[3] = static_cast<std::uint32_t>(c.particles.size());
  MlsStoredWeights refused;
  EXPECT_FALSE(refused.assign(offsets, beyond, phi));
  EXPECT_TRUE(refused.empty());
  EXPECT_FALSE(refused.assign(offsets, neighbour, std::vector<double>(phi.begin(), phi.end() - 1)));
}

}  // namespace
}  // namespace mls_stored_weights_test
}  // namespace talus
