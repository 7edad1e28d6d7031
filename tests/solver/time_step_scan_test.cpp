// The time step's vectorised scan (solver/time_step_scan.hpp, Edo & Matsubara 2015, eq. 60): the same
// maximum of c_p + |v_p| as the scalar formula, bit for bit, on every instruction-set path, with the
// volume cap of separated particles, run lengths that leave a tail, and a NaN rate skipped as
// std::max skips it.
#include "talus/core/simd_dispatch.hpp"
#include "talus/solver/time_step_scan.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstring>
#include <random>
#include <vector>

namespace talus {
namespace time_step_scan_test {
namespace {

struct ParticleRun {
  std::vector<double> volume, volume0, mass, v[3];
  explicit ParticleRun(std::size_t n, unsigned seed) : volume(n), volume0(n), mass(n), v{std::vector<double>(n), std::vector<double>(n), std::vector<double>(n)} {
    std::mt19937 rng(seed);
    std::uniform_real_distribution<double> u(0.5, 1.5), s(-3.0, 3.0);
    for (std::size_t p = 0; p < n; ++p) {
      volume0[p] = 1e-6 * u(rng);
      volume[p] = volume0[p] * (p % 7 == 0 ? 1.6 : u(rng));  // some past the cap of 1.2 V0
      mass[p] = 1.6e-3 * u(rng);
      for (auto& c : v) c[p] = s(rng);
    }
  }
  WaveRateFields fields() const { return {volume.data(), volume0.data(), mass.data(), {v[0].data(), v[1].data(), v[2].data()}}; }
};

/// The scalar scan's formula (Solver::stable_time_step, BodyMaterials::wave_speed_volume).
double scalar_max(const ParticleRun& r, const WaveRateRule& rule, std::size_t begin, std::size_t end) {
  double best = 0.0;
  for (std::size_t p = begin; p < end; ++p) {
    const double volume = rule.cap_ratio > 0.0 && r.volume[p] > rule.cap_ratio * r.volume0[p]
                              ? rule.cap_ratio * r.volume0[p]
                              : r.volume[p];
    const double c = std::sqrt(rule.modulus * volume / r.mass[p]);
    const double speed = std::sqrt(r.v[0][p] * r.v[0][p] + r.v[1][p] * r.v[1][p] + r.v[2][p] * r.v[2][p]);
    best = std::max(best, c + speed);
  }
  return best;
}

TEST(TimeStepScan, SameMaximumAsTheScalarFormulaOnEveryPath) {
  ParticleRun r(1003, 5);
  r.v[1][500] = std::nan("");  // a NaN rate: skipped
  const std::vector<std::string> paths = available_isas();
  ASSERT_GE(paths.size(), 2u);
  for (const WaveRateRule rule : {WaveRateRule{2.7e6, 0.0}, WaveRateRule{2.7e6, 1.2}})
    for (auto [begin, end] : {std::pair<std::size_t, std::size_t>{0, 1003}, {3, 3}, {5, 12}, {1, 998}}) {
      const double expected = scalar_max(r, rule, begin, end);
      for (const std::string& path : paths) {
        select_isa(path);
        const double got = max_wave_rate_lanes(r.fields(), rule, begin, end);
        EXPECT_EQ(std::memcmp(&got, &expected, sizeof(double)), 0)
            << path << " [" << begin << ", " << end << ") cap " << rule.cap_ratio << ": " << got << " vs " << expected;
      }
      select_isa("auto");
    }
  // The cap can decide the maximum: without it the particles at 1.6 V0 are the fastest.
  EXPECT_NE(scalar_max(r, {2.7e6, 0.0}, 0, 1003), scalar_max(r, {2.7e6, 1.2}, 0, 1003));
}

}  // namespace
}  // namespace time_step_scan_test
}  // namespace talus
