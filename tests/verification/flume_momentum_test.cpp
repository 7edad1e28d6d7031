// Momentum balance of the flume (issue 7 "Verification"; docs/flume.md): while the whole mass slides
// on the inclined plane, its centre of mass accelerates along the plane at g (sin theta - tan delta
// cos theta), whatever the sand does inside: the only forces along the plane are gravity and the
// Coulomb friction mu N of the sliding bed nodes (Abe, Johansson & Konagai 2005, eq. 14-16). inputs/benchmarks/sand_slide_incline.json:
// theta = 31.4 deg done by tilting gravity on a flat grid, delta = 29 deg.
#include "talus/diagnostics/runout.hpp"
#include "talus/scene/scene_json.hpp"
#include "talus/solver/solver.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <vector>

namespace talus {
namespace flume_momentum_test {
namespace {

constexpr double kG = 9.81;

struct Slide {
  std::vector<RunoutSample> samples;  // every 0.01 s
  double acceleration = 0.0;          // of the centre of mass along the plane, m/s^2
};

// Runs `scene` to its end and checks the premise (the whole mass slides all along), the mass and
// that no particle sinks below the bed; returns the centre of mass's acceleration along the plane.
Slide slide(const Scene& scene) {
  Solver solver(scene);
  const double mass0 = measure_runout(solver.particles(), FlumeCoordinates(), 0.995, 0.005).mass;
  Slide r;
  double next = 0.0;
  while (!solver.finished()) {
    solver.step();
    if (solver.time() >= next || solver.finished()) {
      RunoutSample s = measure_runout(solver.particles(), FlumeCoordinates(), 0.995, 0.005);
      s.time = solver.time();
      r.samples.push_back(s);
      next += 0.01;
    }
  }
  // The premise: the rearmost 0.5% of the mass keeps moving down the plane in every 0.05 s.
  for (std::size_t k = 5; k < r.samples.size(); k += 5)
    EXPECT_GT(r.samples[k].tail, r.samples[k - 5].tail + 1e-4) << "the tail stopped by t = " << r.samples[k].time;
  // Least-squares slope of the centre-of-mass velocity along the plane over [0.1 s, end], after the
  // settling of the initially stress-free layer.
  double st = 0, sv = 0, stt = 0, stv = 0;
  int n = 0;
  for (const RunoutSample& s : r.samples) {
    if (s.time < 0.1) continue;
    st += s.time;
    sv += s.centre_velocity_s;
    stt += s.time * s.time;
    stv += s.time * s.centre_velocity_s;
    ++n;
  }
  r.acceleration = (n * stv - st * sv) / (n * stt - st * st);
  // Mass is conserved and no particle is below the bed.
  const ParticleStore& P = solver.particles();
  double mass = 0.0;
  for (std::size_t p = 0; p < P.size(); ++p) {
    mass += P.mass[p];
    EXPECT_GE(P.x[2][p], -1e-9) << "particle " << P.id[p] << " sank below the bed";
  }
  EXPECT_NEAR(mass, mass0, 1e-12 * mass0);
  return r;
}

Scene benchmark(const char* name, double theta, double mu) {
  const Scene scene = read_scene_file(std::string(TALUS_SOURCE_DIR) + "/inputs/benchmarks/" + name);
  EXPECT_NEAR(scene.gravity[0], kG * std::sin(theta), 1e-12);
  EXPECT_NEAR(scene.gravity[2], -kG * std::cos(theta), 1e-12);
  EXPECT_NEAR(scene.walls[2][0].friction_coefficient, mu, 1e-12);
  return scene;
}

TEST(FlumeMomentum, SlidingSandAcceleratesAtGSinThetaMinusTanDeltaCosTheta) {
  const double theta = 31.4 * M_PI / 180.0, mu = std::tan(29.0 * M_PI / 180.0);
  const double expected = kG * (std::sin(theta) - mu * std::cos(theta));  // 0.4697 m/s^2
  // (measured: the tail moves 0.05 m in 0.5 s, the front 0.25 m)
  const double acceleration = slide(benchmark("sand_slide_incline.json", theta, mu)).acceleration;
  std::printf("sliding sand: centre-of-mass acceleration %.4f m/s^2, expected %.4f (%+.2f%%)\n", acceleration, expected,
              100.0 * (acceleration / expected - 1.0));
  EXPECT_NEAR(acceleration, expected, 0.05 * expected);  // issue 7: within 5% (measured +0.55%)
  EXPECT_NEAR(acceleration, expected, 0.015 * expected);  // not a target: a regression bound
}

// The same layer near its sliding threshold, mu = 0.55 on 30 degrees (tan 30 = 0.577): the
// acceleration is small (0.2324 m/s^2), so the figure of merit is the effective friction
// tan theta - a / (g cos theta) against mu. An undamped elastic block there slides with a friction
// 0.007-0.2 too low, more so on finer grids (docs/verification.md "Near the sliding threshold"); the
// sand, which dissipates by plasticity, does not: -0.0009, -0.0006, -0.0007 at h = 0.01, 0.005, 0.0025.
TEST(FlumeMomentum, SandNearTheSlidingThresholdSlidesWithTheBedsFriction) {
  const double theta = 30.0 * M_PI / 180.0, mu = 0.55;
  const double acceleration = slide(benchmark("sand_slide_near_threshold.json", theta, mu)).acceleration;
  const double mu_effective = std::tan(theta) - acceleration / (kG * std::cos(theta));
  std::printf("sand near the threshold: acceleration %.4f m/s^2, rigid %.4f; effective friction %.4f (%+.4f)\n",
              acceleration, kG * (std::sin(theta) - mu * std::cos(theta)), mu_effective, mu_effective - mu);
  EXPECT_LT(std::abs(mu_effective - mu), 0.002);  // measured -0.0009 (the elastic block at h = L/4: -0.0068)
}

}  // namespace
}  // namespace flume_momentum_test
}  // namespace talus
