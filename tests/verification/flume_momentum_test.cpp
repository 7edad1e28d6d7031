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

TEST(FlumeMomentum, SlidingSandAcceleratesAtGSinThetaMinusTanDeltaCosTheta) {
  const Scene scene = read_scene_file(std::string(TALUS_SOURCE_DIR) + "/inputs/benchmarks/sand_slide_incline.json");
  const double theta = 31.4 * M_PI / 180.0, mu = std::tan(29.0 * M_PI / 180.0), g = 9.81;
  ASSERT_NEAR(scene.gravity[0], g * std::sin(theta), 1e-12);
  ASSERT_NEAR(scene.gravity[2], -g * std::cos(theta), 1e-12);
  ASSERT_NEAR(scene.walls[2][0].friction_coefficient, mu, 1e-12);
  const double expected = g * (std::sin(theta) - mu * std::cos(theta));  // 0.4697 m/s^2

  Solver solver(scene);
  const double mass0 = measure_runout(solver.particles(), FlumeCoordinates(), 0.995, 0.005).mass;
  std::vector<RunoutSample> samples;
  double next = 0.0;
  while (!solver.finished()) {
    solver.step();
    if (solver.time() >= next || solver.finished()) {
      RunoutSample s = measure_runout(solver.particles(), FlumeCoordinates(), 0.995, 0.005);
      s.time = solver.time();
      samples.push_back(s);
      next += 0.01;
    }
  }
  // The premise: the whole mass slides all along. The rearmost 0.5% of the mass keeps moving down
  // the plane in every 0.05 s (measured: the tail moves 0.05 m in 0.5 s, the front 0.25 m).
  for (std::size_t k = 5; k < samples.size(); k += 5)
    EXPECT_GT(samples[k].tail, samples[k - 5].tail + 1e-4) << "the tail stopped by t = " << samples[k].time;
  // Least-squares slope of the centre-of-mass velocity along the plane over [0.1 s, end], after the
  // settling of the initially stress-free layer.
  double st = 0, sv = 0, stt = 0, stv = 0;
  int n = 0;
  for (const RunoutSample& s : samples) {
    if (s.time < 0.1) continue;
    st += s.time;
    sv += s.centre_velocity_s;
    stt += s.time * s.time;
    stv += s.time * s.centre_velocity_s;
    ++n;
  }
  const double acceleration = (n * stv - st * sv) / (n * stt - st * st);
  std::printf("sliding sand: centre-of-mass acceleration %.4f m/s^2, expected %.4f (%+.2f%%)\n", acceleration, expected,
              100.0 * (acceleration / expected - 1.0));
  EXPECT_NEAR(acceleration, expected, 0.05 * expected);  // issue 7: within 5% (measured +0.55%)
  EXPECT_NEAR(acceleration, expected, 0.015 * expected);  // not a target: a regression bound
  // Mass is conserved and no particle is below the bed.
  const ParticleStore& P = solver.particles();
  double mass = 0.0;
  for (std::size_t p = 0; p < P.size(); ++p) {
    mass += P.mass[p];
    ASSERT_GE(P.x[2][p], -1e-9) << "particle " << P.id[p] << " sank below the bed";
  }
  EXPECT_NEAR(mass, mass0, 1e-12 * mass0);
}

}  // namespace
}  // namespace flume_momentum_test
}  // namespace talus
