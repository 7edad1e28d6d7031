#pragma once
// Runs of the papers' elastic benchmarks with and without MLS smoothing (Edo & Matsubara 2015, sec. 4), shared by
// the MLS verification tests; each prints its measures so the test log carries the numbers.
#include "benchmark_metrics.hpp"

#include <gtest/gtest.h>

#include <cstdio>
#include <string>

namespace talus::test {

inline Scene with_mls(Scene s, MlsBasis basis, double radius_factor, const char* axes) {
  s.smoothing.enabled = true;
  s.smoothing.mls.basis = basis;
  s.smoothing.mls.radius_factor = radius_factor;
  for (int d = 0; d < 3; ++d) s.smoothing.mls.axes[d] = std::string(axes).find(char('x' + d)) != std::string::npos;
  return s;
}

/// The shipped MLS input inputs/benchmarks/<name>_mls.json is the benchmark <name> with `shape` and
/// the paper's fit (cubic along x, radius 2 cells) that the tests verify: the same scene otherwise.
inline void expect_shipped_mls_input(const std::string& name, ShapeKind shape) {
  const Scene shipped = read_scene_file(std::string(TALUS_SOURCE_DIR) + "/inputs/benchmarks/" + name + "_mls.json");
  const Scene verified = with_mls(benchmark_scene(name, shape, SchemeKind::Musl), MlsBasis::Cubic, 2.0, "x");
  EXPECT_EQ(shipped.shape, verified.shape) << name;
  EXPECT_EQ(shipped.scheme, verified.scheme) << name;
  EXPECT_TRUE(shipped.smoothing.enabled) << name;
  EXPECT_EQ(shipped.smoothing.mls.basis, verified.smoothing.mls.basis) << name;
  EXPECT_EQ(shipped.smoothing.mls.radius_factor, verified.smoothing.mls.radius_factor) << name;
  EXPECT_EQ(shipped.smoothing.mls.axes, verified.smoothing.mls.axes) << name;
  EXPECT_TRUE(shipped.smoothing.bodies.empty()) << name;
  EXPECT_EQ(shipped.end_time, verified.end_time) << name;
  EXPECT_EQ(shipped.courant, verified.courant) << name;
  EXPECT_EQ(shipped.gravity, verified.gravity) << name;
  EXPECT_EQ(shipped.gravity_ramp_time, verified.gravity_ramp_time) << name;
  EXPECT_EQ(shipped.grid.h, verified.grid.h) << name;
  EXPECT_EQ(shipped.grid.cells, verified.grid.cells) << name;
  ASSERT_EQ(shipped.bodies.size(), verified.bodies.size()) << name;
  for (std::size_t b = 0; b < shipped.bodies.size(); ++b) {
    EXPECT_EQ(shipped.bodies[b].velocity, verified.bodies[b].velocity) << name;
    EXPECT_EQ(shipped.bodies[b].particles_per_cell, verified.bodies[b].particles_per_cell) << name;
  }
}

inline ColumnError column(const Scene& s, const char* label) {
  Solver solver(s);
  run_to_end(solver);
  const auto e = column_error(solver, 1e6, 1.0, s.gravity[0], 50.0);
  std::printf("column %-8s %-22s L2 %.5f roughness %.5f unsmoothed %lld\n", to_string(s.shape), label, e.l2,
              e.roughness, (long long)solver.unsmoothed_total());
  return e;
}

struct Bar { double ratio = 0.0, roughness = 0.0; };
inline Bar bar(const Scene& s, const char* label) {
  Solver solver(s);
  run_to_end(solver);
  const double E = 1e6, c = 1000.0, v0 = s.bodies[0].velocity[0];
  const double front = c * solver.time();
  const double exact = -E * std::abs(v0) / c;  // Edo & Matsubara 2015, eq. 63
  const Profile prof = axial_profile(solver.particles());
  double sum = 0.0, rough = 0.0;
  int count = 0, rc = 0;
  for (std::size_t k = 0; k < prof.x.size(); ++k)
    if (prof.x[k] > 3.0 && prof.x[k] < front - 6.0) {
      sum += prof.stress[k];
      ++count;
      if (k > 0 && k + 1 < prof.x.size()) {
        const double d2 = prof.stress[k + 1] - 2 * prof.stress[k] + prof.stress[k - 1];
        rough += d2 * d2;
        ++rc;
      }
    }
  Bar b;
  b.ratio = sum / count / exact;
  b.roughness = std::sqrt(rough / rc) / std::abs(exact);
  std::printf("dynamic bar %-8s %-14s ratio %.5f roughness %.5f unsmoothed %lld\n", to_string(s.shape), label, b.ratio,
              b.roughness, (long long)solver.unsmoothed_total());
  return b;
}

struct Energy { double max_gain = 0.0, max_loss = 0.0, final_drift = 0.0; };
inline Energy walls(const Scene& s, const char* label) {
  Solver solver(s);
  Energy h;
  const double e0 = solver.energies().total();
  while (!solver.finished()) {
    solver.step();
    const double d = (solver.energies().total() - e0) / std::abs(e0);
    h.max_gain = std::max(h.max_gain, d);
    h.max_loss = std::max(h.max_loss, -d);
    h.final_drift = d;
  }
  std::printf("walls %-8s %-14s max gain %.5f max loss %.5f final %.5f unsmoothed %lld steps %lld\n", to_string(s.shape),
              label, h.max_gain, h.max_loss, h.final_drift, (long long)solver.unsmoothed_total(), (long long)solver.step_count());
  return h;
}

}  // namespace talus::test
