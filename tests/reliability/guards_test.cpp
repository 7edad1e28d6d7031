// Instability guards and the hard cases of issue 9: each hard scene either runs stably or stops
// with a one-line diagnosis (step, time, particle, field, value) after writing its last good state;
// it never crashes and never writes a non-finite value.
#include "../solver/scene_fixtures.hpp"
#include "reliability_fixtures.hpp"
#include "talus/core/error.hpp"
#include "talus/io/checkpoint.hpp"
#include "talus/driver/run_driver.hpp"
#include "talus/solver/solver.hpp"
#include "talus/solver/stability_guards.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <limits>

namespace talus {
namespace {

namespace fs = std::filesystem;

std::string instability_of(Solver& solver, int max_steps = 100000) {
  try {
    for (int i = 0; i < max_steps && !solver.finished(); ++i) solver.step();
  } catch (const Error& e) {
    EXPECT_EQ(e.kind(), Error::Kind::Instability) << e.what();
    return e.what();
  }
  return "";
}

void expect_diagnosis(const std::string& message, const std::string& field) {
  EXPECT_EQ(message.rfind("step ", 0), 0u) << message;
  EXPECT_NE(message.find(", t = "), std::string::npos) << message;
  EXPECT_NE(message.find("particle "), std::string::npos) << message;
  EXPECT_NE(message.find(field), std::string::npos) << message;
  EXPECT_EQ(message.find('\n'), std::string::npos) << message;
}

TEST(Guards, NonFiniteParticleFieldIsDiagnosedWithItsName) {
  Solver solver(test::tumbling_block_scene());
  solver.step();
  auto& P = solver.particles();
  P.strain[2][17] = std::numeric_limits<double>::infinity();  // a field the step itself never reads
  const std::int64_t id = P.id[17];
  const std::string m = instability_of(solver, Solver::kFieldCheckInterval);
  expect_diagnosis(m, "field strain2 = inf");
  EXPECT_NE(m.find("particle " + std::to_string(id) + " "), std::string::npos) << m;
}

TEST(Guards, CflBreachIsDiagnosed) {
  // Much faster than the wave speed with a Courant number near 1: the particles move most of a
  // cell per step; a tight guard turns that into a diagnosed CFL breach.
  Scene scene = test::free_fall_scene("musl");
  scene.courant = 0.9;
  scene.bodies[0].velocity = Vec3(0, 0, -200.0);
  scene.guards.max_step_displacement = 0.5;
  Solver solver(scene);
  expect_diagnosis(instability_of(solver), "field displacement");
}

TEST(Guards, EnergyGrowthBeyondTheFactorStops) {
  const Scene scene = test::free_fall_scene("musl");
  Solver solver(scene);
  EnergyBudget e0 = solver.energies();
  EnergyGuard guard(scene, solver.particles(), e0);
  EnergyBudget e = e0;
  e.kinetic = e0.kinetic + 0.5 * guard.available();
  EXPECT_NO_THROW(guard.check(e, solver.particles(), scene, 10, 0.01));
  e.kinetic = e0.kinetic + 1.5 * guard.available();
  try {
    guard.check(e, solver.particles(), scene, 10, 0.01);
    ADD_FAILURE() << "no error";
  } catch (const Error& err) {
    EXPECT_EQ(err.kind(), Error::Kind::Instability);
    expect_diagnosis(err.what(), "energy_growth_factor");
  }
  // Potential energy released by a fall is available energy: converting it into kinetic is fine.
  e = e0;
  e.gravity = e0.gravity - 1000.0;
  e.kinetic = e0.kinetic + 1000.0;
  EXPECT_NO_THROW(guard.check(e, solver.particles(), scene, 20, 0.02));
  e.gravity = e0.gravity;  // then bounced back up: 1000 J was released once, so that much is allowed
  EXPECT_NO_THROW(guard.check(e, solver.particles(), scene, 30, 0.03));
}

/// Runs a scene through the run driver; returns the diagnosis ("" if it ran to the end) after
/// checking that the folder holds only readable, finite output and, on failure, a checkpoint of
/// the last good state that restarts.
std::string run_hard_case(const Scene& scene, const std::string& name) {
  const fs::path dir = test::temp_dir(name);
  RunOptions options;
  options.out_dir = dir.string();
  options.progress = false;
  options.handle_signals = false;
  std::string diagnosis;
  Solver solver(scene);
  try {
    run_scene(solver, options);
  } catch (const Error& e) {
    EXPECT_EQ(e.kind(), Error::Kind::Instability) << e.what();
    diagnosis = e.what();
  }
  test::expect_readable_run_folder(dir);
  if (!diagnosis.empty()) {
    expect_diagnosis(diagnosis, "position (");
    EXPECT_NE(diagnosis.find("last good state"), std::string::npos) << diagnosis;
    const std::string cp = (dir / "checkpoint.h5").string();
    Solver again(scene);
    EXPECT_NO_THROW(restore_checkpoint(again, read_checkpoint(cp), cp));
    EXPECT_LT(again.step_count(), 1000000);
  }
  fs::remove_all(dir);
  return diagnosis;
}

// Seed 000's column: a 1D bar of E = 1e6, rho = 1, L0 = 50 under its own weight rho b L0 = 12500
// (|g| = 250) with 100 particles along the bar (2 per cell of 1.0), linear MPM: the particles at
// the top cross cells while the column oscillates, the classic cell-crossing noise.
TEST(HardCases, Seed000ColumnUnderGravityWithLinearShapes) {
  Scene scene = parse_scene(R"({
    "name": "column",
    "grid": { "origin": [0, 0, 0], "size": [60, 1, 1], "cell_size": 1.0 },
    "gravity": [-250, 0, 0],
    "time": { "end": 0.3, "courant": 0.2 },
    "materials": { "m": { "density": 1.0, "young": 1.0e6, "poisson": 0.0 } },
    "bodies": [ { "name": "column", "material": "m", "box": { "min": [0, 0, 0], "max": [50, 1, 1] },
                  "particles_per_cell": 2 } ],
    "boundaries": { "x-": "fixed", "x+": "open", "y-": "slip", "y+": "slip", "z-": "slip", "z+": "slip" },
    "output": { "frame_interval": 0.05, "history_interval": 0.001 }
  })", "column");
  const std::string d = run_hard_case(scene, "column");
  RecordProperty("diagnosis", d);
  std::printf("column: %s\n", d.empty() ? "ran to the end" : d.c_str());
}

TEST(HardCases, BlockImpactingAWallAtHighSpeed) {
  // 100 m/s into a fixed wall: three times the block's wave speed (~37 m/s).
  Scene scene = parse_scene(R"({
    "name": "impact",
    "grid": { "origin": [0, 0, 0], "size": [0.8, 0.4, 0.4], "cell_size": 0.04 },
    "gravity": [0, 0, 0],
    "time": { "end": 0.01, "courant": 0.3 },
    "materials": { "m": { "density": 1000.0, "young": 1.0e6, "poisson": 0.3 } },
    "bodies": [ { "name": "block", "material": "m", "box": { "min": [0.4, 0.12, 0.12], "max": [0.72, 0.28, 0.28] },
                  "particles_per_cell": 2, "velocity": [100, 0, 0] } ],
    "boundaries": { "x+": "fixed" },
    "output": { "frame_interval": 0.001 }
  })", "impact");
  const std::string d = run_hard_case(scene, "impact");
  std::printf("impact: %s\n", d.empty() ? "ran to the end" : d.c_str());
}

TEST(HardCases, NearEmptyNodes) {
  // A light, soft dust layer on a stiff block: nodes at the dust's edge hold a tiny mass next to
  // nodes of the block (the nodal mass ratio across the stencil is ~1e-8).
  Scene scene = parse_scene(R"({
    "name": "dust",
    "grid": { "origin": [0, 0, 0], "size": [0.4, 0.4, 0.4], "cell_size": 0.04 },
    "time": { "end": 0.05, "courant": 0.3 },
    "materials": { "m": { "density": 1000.0, "young": 1.0e6, "poisson": 0.3 },
                   "dust": { "density": 1e-5, "young": 1.0e-2, "poisson": 0.3 } },
    "bodies": [ { "name": "block", "material": "m", "box": { "min": [0.08, 0.08, 0.0], "max": [0.32, 0.32, 0.16] } },
                { "name": "dust", "material": "dust", "box": { "min": [0.08, 0.08, 0.16], "max": [0.32, 0.32, 0.18] },
                  "particles_per_cell": 4, "velocity": [0, 0, 1] } ],
    "boundaries": { "z-": "fixed", "z+": "open" },
    "output": { "frame_interval": 0.01 }
  })", "dust");
  const std::string d = run_hard_case(scene, "dust");
  std::printf("near-empty nodes: %s\n", d.empty() ? "ran to the end" : d.c_str());
}

TEST(HardCases, StrayParticleJustPastANode) {
  Scene scene = test::free_fall_scene("musl");
  scene.end_time = 0.05;
  scene.gravity = Vec3(0, 0, -9.81);
  Solver solver(scene);
  auto& P = solver.particles();
  // Move one particle to 1e-9 h past a node, away from the others, with a large stress.
  P.x[0][0] = 0.05 * 2 + 1e-9 * 0.05;
  P.x[1][0] = 0.05 * 1 + 1e-9 * 0.05;
  P.x[2][0] = 0.05 * 4 + 1e-9 * 0.05;
  P.stress[0][0] = 1e4;
  const std::string d = instability_of(solver);
  std::printf("stray particle: %s\n", d.empty() ? "ran to the end" : d.c_str());
  for (std::size_t p = 0; p < P.size(); ++p)
    for (int c = 0; c < 3; ++c) ASSERT_TRUE(std::isfinite(P.x[c][p]) || !d.empty());
}

TEST(HardCases, ParticlesAtTheDomainEdge) {
  // The block fills the grid from face to face along x and y, and touches the floor: particles sit
  // half a spacing from every face but the top. Slip walls hold it; through open x faces it flows out.
  const std::string json = R"({
    "name": "edge",
    "grid": { "origin": [0, 0, 0], "size": [0.4, 0.4, 0.4], "cell_size": 0.04 },
    "time": { "end": 0.1, "courant": 0.3 },
    "materials": { "m": { "density": 1000.0, "young": 1.0e6, "poisson": 0.3 } },
    "bodies": [ { "name": "block", "material": "m", "box": { "min": [0, 0, 0], "max": [0.4, 0.4, 0.2] },
                  "velocity": [VX, 0, 0] } ],
    "boundaries": { "x-": "XP", "x+": "XP", "z+": "open" },
    "output": { "frame_interval": 0.02 }
  })";
  auto scene_with = [&](const char* vx, const char* xp) {
    std::string j = json;
    j.replace(j.find("VX"), 2, vx);
    j.replace(j.find("XP"), 2, xp);
    j.replace(j.find("XP"), 2, xp);
    return parse_scene(j, "edge");
  };
  EXPECT_EQ(run_hard_case(scene_with("0", "slip"), "edge_slip"), "");
  // open x faces are outflow boundaries: the particles pushed through x+ are removed and counted
  EXPECT_EQ(run_hard_case(scene_with("3", "open"), "edge_open"), "");
  Solver solver(scene_with("3", "open"));
  const std::size_t seeded = solver.particles().size();
  while (!solver.finished()) solver.step();
  EXPECT_GT(solver.outflow_particles(), 0);
  EXPECT_EQ(static_cast<std::int64_t>(solver.particles().size()) + solver.outflow_particles(),
            static_cast<std::int64_t>(seeded));
}

TEST(HardCases, DruckerPragerApexStates) {
  // Cohesionless sand pulled apart: two bodies moving away from each other put the particles at
  // their interface in tension, i.e. on the apex of the cone.
  Scene scene = parse_scene(R"({
    "name": "apex",
    "grid": { "origin": [0, 0, 0], "size": [0.8, 0.2, 0.3], "cell_size": 0.025 },
    "time": { "end": 0.08, "courant": 0.3 },
    "materials": { "sand": { "model": "drucker_prager", "density": 1600.0, "young": 2.0e6, "poisson": 0.3,
                             "friction_angle": 30.0, "dilatancy_angle": 5.0, "cohesion": 0.0 } },
    "bodies": [ { "name": "left", "material": "sand", "box": { "min": [0.2, 0.05, 0.0], "max": [0.4, 0.15, 0.1] },
                  "velocity": [-2, 0, 0] },
                { "name": "right", "material": "sand", "box": { "min": [0.4, 0.05, 0.0], "max": [0.6, 0.15, 0.1] },
                  "velocity": [2, 0, 0] } ],
    "boundaries": { "z-": { "type": "friction", "friction_coefficient": 0.3 }, "z+": "open" },
    "output": { "frame_interval": 0.02 }
  })", "apex");
  const std::string d = run_hard_case(scene, "apex");
  std::printf("apex: %s\n", d.empty() ? "ran to the end" : d.c_str());
}

TEST(HardCases, SteepSixtyDegreeSlopeWithLowFriction) {
  // A 60 degree slope, emulated on the flat grid by rotating gravity: g = 9.81 (sin 60, 0, -cos 60),
  // friction 0.05 on the floor (far below tan 60), so the block accelerates down the whole grid
  // into the x+ wall.
  const double s = std::sin(M_PI / 3), c = std::cos(M_PI / 3);
  Scene scene = parse_scene(fmt::format(R"({{
    "name": "steep",
    "grid": {{ "origin": [0, 0, 0], "size": [1.6, 0.32, 0.32], "cell_size": 0.04 }},
    "gravity": [{}, 0, {}],
    "time": {{ "end": 0.6, "courant": 0.3 }},
    "materials": {{ "m": {{ "density": 1000.0, "young": 1.0e6, "poisson": 0.3 }} }},
    "bodies": [ {{ "name": "block", "material": "m", "box": {{ "min": [0.04, 0.08, 0.0], "max": [0.28, 0.24, 0.12] }} }} ],
    "boundaries": {{ "z-": {{ "type": "friction", "friction_coefficient": 0.05 }}, "z+": "open" }},
    "output": {{ "frame_interval": 0.1 }}
  }})", 9.81 * s, -9.81 * c), "steep");
  const std::string d = run_hard_case(scene, "steep");
  std::printf("steep slope: %s\n", d.empty() ? "ran to the end" : d.c_str());
}

}  // namespace
}  // namespace talus
