// Open faces are outflow boundaries: particles that cross one are removed at the end of their
// step, with their mass and energy counted, so the energy budget still closes and a restart
// continues bit for bit. The time step that the stress pass prepares for the next step is that of
// a scan of the particles, also when the fastest ones have just left.
#include "scene_fixtures.hpp"
#include "talus/solver/solver.hpp"

#include <fmt/core.h>
#include <gtest/gtest.h>

#include <algorithm>
#include <cstring>

namespace talus {
namespace outflow_test {
namespace {

// An elastic block sliding on a frictionless floor through the open x+ face of the grid.
Scene sliding_out_scene() {
  const std::string json = R"({
    "name": "outflow",
    "grid": { "origin": [0, 0, 0], "size": [0.6, 0.2, 0.3], "cell_size": 0.025 },
    "time": { "end": 0.12, "courant": 0.3 },
    "materials": { "m": { "density": 1000.0, "young": 1.0e6, "poisson": 0.3 } },
    "bodies": [ { "name": "block", "material": "m", "box": { "min": [0.3, 0.05, 0.0], "max": [0.5, 0.15, 0.1] },
                  "particles_per_cell": 2, "velocity": [2.0, 0.0, 0.0] } ],
    "boundaries": { "x-": "slip", "x+": "open", "y-": "slip", "y+": "slip", "z-": "slip", "z+": "open" }
  })";
  return parse_scene(json, "sliding_out_scene");
}

double total_mass(const ParticleStore& P) {
  double m = 0.0;
  for (double v : P.mass) m += v;
  return m;
}

TEST(Outflow, ParticlesLeavingAnOpenFaceAreRemovedAndCounted) {
  Solver solver(sliding_out_scene());
  const std::size_t seeded = solver.particles().size();
  const double m0 = total_mass(solver.particles());
  const EnergyBudget e0 = solver.energies();
  while (!solver.finished()) solver.step();
  const ParticleStore& P = solver.particles();
  // the block front (x = 0.5 + 2 m/s * 0.12 s = 0.74 m) went 0.14 m past the face at x = 0.6
  EXPECT_GT(solver.outflow_particles(), 0);
  EXPECT_LT(P.size(), seeded);
  EXPECT_EQ(static_cast<std::int64_t>(P.size()) + solver.outflow_particles(), static_cast<std::int64_t>(seeded));
  EXPECT_NEAR(total_mass(P) + solver.outflow_mass(), m0, 1e-12 * m0);
  for (std::size_t p = 0; p < P.size(); ++p) EXPECT_LE(P.x[0][p], 0.6) << p;  // none beyond the face
  // the energy that left is in the budget: it still closes (no friction, elastic, gravity along -z)
  const EnergyBudget e1 = solver.energies();
  EXPECT_GT(e1.outflow, 0.1 * e0.kinetic);
  EXPECT_NEAR(e1.total(), e0.total(), 0.01 * e0.kinetic);
}

// run.json's end.outflow_by_face: the mass and particles that left through each face. Only the share
// through x+ was kept; a block thrown out sideways and one through the floor could not be told apart.
TEST(Outflow, EachFaceCountsWhatLeftThroughIt) {
  const std::string json = R"({
    "name": "three_ways_out",
    "grid": { "origin": [0, 0, 0], "size": [0.6, 0.4, 0.3], "cell_size": 0.025 },
    "gravity": [0, 0, -9.81],
    "time": { "end": 0.1, "courant": 0.3 },
    "materials": { "m": { "density": 1000.0, "young": 1.0e6, "poisson": 0.3 } },
    "bodies": [ { "name": "east", "material": "m", "box": { "min": [0.45, 0.25, 0.1], "max": [0.55, 0.35, 0.15] },
                  "particles_per_cell": 2, "velocity": [3.0, 0.0, 0.0] },
                { "name": "south", "material": "m", "box": { "min": [0.1, 0.02, 0.1], "max": [0.2, 0.12, 0.15] },
                  "particles_per_cell": 2, "velocity": [0.0, -3.0, 0.0] },
                { "name": "down", "material": "m", "box": { "min": [0.3, 0.15, 0.02], "max": [0.4, 0.25, 0.07] },
                  "particles_per_cell": 2, "velocity": [0.0, 0.0, -3.0] } ],
    "boundaries": { "x-": "slip", "x+": "open", "y-": "open", "y+": "open", "z-": "open", "z+": "slip" }
  })";
  Solver a(parse_scene(json, "three_ways_out"));
  while (a.outflow_particles() == 0) a.step();
  Solver b(parse_scene(json, "three_ways_out"));
  b.restore(a.particles(), a.state());  // the counts so far go with the state
  while (!a.finished()) {
    a.step();
    b.step();
  }
  const OutflowFaces faces = a.outflow_faces();
  EXPECT_GT(faces.particles[1], 0);  // x+
  EXPECT_GT(faces.particles[2], 0);  // y-
  EXPECT_GT(faces.particles[4], 0);  // z-
  EXPECT_EQ(faces.particles[0] + faces.particles[3] + faces.particles[5], 0);  // x-, z+ are walls; nothing went y+
  EXPECT_EQ(faces.particles[1] + faces.particles[2] + faces.particles[4], a.outflow_particles());
  double mass = 0.0;
  for (double m : faces.mass) mass += m;
  EXPECT_NEAR(mass, a.outflow_mass(), 1e-12 * a.outflow_mass());
  EXPECT_EQ(faces.mass[OutflowFaces::kXPlus], a.outflow_mass_x_plus());  // the runout's share: the same sum
  const OutflowFaces restored = b.outflow_faces();
  EXPECT_EQ(restored.particles, faces.particles);
  EXPECT_EQ(std::memcmp(restored.mass.data(), faces.mass.data(), sizeof(faces.mass)), 0);
}

// A particle past two open faces at once (a corner) counts once: at x+ first (ahead of the runout's
// front), then in the order x-, y-, y+, z-, z+.
TEST(Outflow, APastACornerCountsAtOneFace) {
  GatherOptions limits;
  limits.lo = {0.0, 0.0, 0.0};
  limits.hi = {1.0, 1.0, 1.0};
  for (auto& axis : limits.open) axis = {true, true};
  const double past_x_plus_and_y_minus[3] = {1.5, -0.5, 0.5}, past_x_minus_and_z_plus[3] = {-0.5, 0.5, 1.5},
               past_y_plus_and_z_minus[3] = {0.5, 1.5, -0.5}, inside[3] = {0.5, 0.5, 0.5};
  EXPECT_EQ(outflow_face(limits, past_x_plus_and_y_minus), 1);
  EXPECT_EQ(outflow_face(limits, past_x_minus_and_z_plus), 0);
  EXPECT_EQ(outflow_face(limits, past_y_plus_and_z_minus), 3);
  EXPECT_EQ(outflow_face(limits, inside), -1);
  limits.open[0][1] = false;  // x+ a wall: past it is no way out
  EXPECT_EQ(outflow_face(limits, past_x_plus_and_y_minus), 2);
}

// guards.max_step_displacement allows up to 2 cells a step. A very soft block under gravity along +x
// next to the open x+ face moves 1.5 cells in its first step (a time step from its slow wave speed):
// the B-spline's next support of the particles that pass the face reached beyond the padded arrays,
// and the step stopped with "left the grid". They leave as outflow.
TEST(Outflow, AParticleMovingMoreThanACellPastAnOpenFaceLeaves) {
  const std::string json = R"({
    "name": "fast_out",
    "grid": { "origin": [0, 0, 0], "size": [1.0, 0.4, 0.4], "cell_size": 0.1 },
    "gravity": [10.0, 0.0, 0.0],
    "time": { "end": 0.12, "courant": 0.5 },
    "solver": { "shape": "bspline2" },
    "materials": { "m": { "density": 1000.0, "young": 166.0, "poisson": 0.0 } },
    "bodies": [ { "name": "block", "material": "m", "box": { "min": [0.7, 0.1, 0.1], "max": [1.0, 0.3, 0.3] },
                  "particles_per_cell": 2 } ],
    "boundaries": { "x-": "slip", "x+": "open", "y-": "slip", "y+": "slip", "z-": "slip", "z+": "slip" },
    "guards": { "max_step_displacement": 2.0 }
  })";
  Solver solver(parse_scene(json, "fast_out"));
  const std::size_t seeded = solver.particles().size();
  const double m0 = total_mass(solver.particles());
  ASSERT_NO_THROW(solver.step());
  EXPECT_GT(solver.outflow_particles(), 0);
  EXPECT_EQ(static_cast<std::int64_t>(solver.particles().size()) + solver.outflow_particles(),
            static_cast<std::int64_t>(seeded));
  EXPECT_NEAR(total_mass(solver.particles()) + solver.outflow_mass(), m0, 1e-12 * m0);
  for (double x : solver.particles().x[0]) EXPECT_LE(x, 1.0);
}

TEST(Outflow, RestoreAfterOutflowContinuesBitForBit) {
  Solver a(sliding_out_scene());
  while (a.outflow_particles() == 0) a.step();
  for (int i = 0; i < 3; ++i) a.step();
  Solver b(sliding_out_scene());
  b.restore(a.particles(), a.state());
  while (!a.finished()) {
    a.step();
    b.step();
  }
  EXPECT_EQ(a.outflow_particles(), b.outflow_particles());
  ASSERT_EQ(a.particles().size(), b.particles().size());
  for (int d = 0; d < 3; ++d) {
    EXPECT_EQ(0, std::memcmp(a.particles().x[d].data(), b.particles().x[d].data(), a.particles().size() * sizeof(double)));
    EXPECT_EQ(0, std::memcmp(a.particles().v[d].data(), b.particles().v[d].data(), a.particles().size() * sizeof(double)));
  }
  EXPECT_EQ(a.energies().total(), b.energies().total());
}

// A fast block leaves through the open x+ face while a slow one stays: the maximum of c_p + |v_p|
// drops when the fast particles are removed. Every step's dt must be the scan of the particles it
// starts with (Solver::stable_time_step), whether it comes from the scan or from the maximum the
// last stress pass kept (MUSL, USL, USAVG), on every scheme.
TEST(Outflow, EveryStepsTimeStepIsTheScanOfItsParticles) {
  for (const char* scheme : {"musl", "usl", "usf", "usavg"}) {
    const std::string json = fmt::format(R"({{
      "name": "time_step_after_outflow",
      "grid": {{ "origin": [0, 0, 0], "size": [0.6, 0.2, 0.3], "cell_size": 0.025 }},
      "time": {{ "end": 0.03, "courant": 0.3 }},
      "solver": {{ "scheme": "{}" }},
      "materials": {{ "m": {{ "density": 1000.0, "young": 1.0e6, "poisson": 0.3 }} }},
      "bodies": [ {{ "name": "fast", "material": "m", "box": {{ "min": [0.45, 0.05, 0.0], "max": [0.55, 0.15, 0.05] }},
                    "particles_per_cell": 2, "velocity": [6.0, 0.0, 0.0] }},
                  {{ "name": "slow", "material": "m", "box": {{ "min": [0.05, 0.05, 0.0], "max": [0.15, 0.15, 0.05] }},
                    "particles_per_cell": 2, "velocity": [0.2, 0.0, 0.0] }} ],
      "boundaries": {{ "x-": "slip", "x+": "open", "y-": "slip", "y+": "slip", "z-": "slip", "z+": "open" }}
    }})",
                                         scheme);
    Solver solver(parse_scene(json, "time_step_after_outflow"));
    const std::size_t seeded = solver.particles().size();
    double first_dt = 0.0;
    int steps = 0;
    while (!solver.finished()) {
      const double scan = solver.stable_time_step();
      const double expected = std::min(scan, solver.scene().end_time - solver.time());
      solver.step();
      const double dt = solver.last_dt();
      if (steps++ == 0) first_dt = dt;
      ASSERT_EQ(std::memcmp(&expected, &dt, sizeof(double)), 0)
          << scheme << ", step " << solver.step_count() << ": dt " << dt << ", the scan gives " << expected;
    }
    EXPECT_EQ(solver.particles().size(), seeded / 2) << scheme;  // the fast block has left
    EXPECT_GT(solver.stable_time_step(), 1.1 * first_dt) << scheme;  // so the time step grew
  }
}

}  // namespace
}  // namespace outflow_test
}  // namespace talus
