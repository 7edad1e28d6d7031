// Elastic blocks on frictional terrain (Abe, Johansson & Konagai 2005, sec. 5, eq. 21-22): the terrain-following grid
// (eq. 19-20) with Coulomb contact at the bed nodes (eq. 14-18), against the rigid-block solutions.
// Quasi-2D like the paper: one cell across, slip side walls. docs/verification.md "Terrain".
#include "bit_identity.hpp"
#include "talus/core/error.hpp"
#include "talus/scene/scene_json.hpp"
#include "talus/solver/solver.hpp"

#include <fmt/core.h>
#include <gtest/gtest.h>
#include <omp.h>

#include <cmath>
#include <string>

namespace talus {
namespace terrain_slide_test {
namespace {

constexpr double kPi = 3.14159265358979323846;
constexpr double kG = 9.81;
const double kTheta = 30.0 * kPi / 180.0;

struct SlideSetup {
  double h = 0.25;                 // cell size (coarse: 4 cells per block edge)
  std::string terrain;             // grid.terrain JSON, empty: flat grid
  double length = 8.0;             // grid length along x
  double mu = 0.3;
  double v0 = 0.0;
  double end = 1.5;
  Vec3 gravity{0.0, 0.0, -kG};
  std::string shape = "linear";
  std::string box = R"("min": [1, 0, 0], "max": [2, 0.25, 1], "frame": "terrain")";
  double young = 1.0e7;
  double width = 0.0;              // grid width along y; 0: one cell
  std::string x_walls = R"("x-": "open", "x+": "open")";
};

Scene slide_scene(const SlideSetup& s) {
  const std::string terrain = s.terrain.empty() ? "" : fmt::format(R"(, "terrain": {})", s.terrain);
  const std::string json = fmt::format(R"({{
    "grid": {{ "origin": [0, 0, 0], "size": [{}, {}, 2], "cell_size": {}{} }},
    "gravity": [{}, {}, {}],
    "time": {{ "end": {}, "courant": 0.3 }},
    "solver": {{ "shape": "{}" }},
    "materials": {{ "m": {{ "density": 1000.0, "young": {}, "poisson": 0.3 }} }},
    "bodies": [ {{ "name": "block", "material": "m", "particles_per_cell": 2, "box": {{ {} }},
                   "velocity": [{}, 0, 0] }} ],
    "boundaries": {{ "z-": {{ "type": "friction", "friction_coefficient": {} }}, "z+": "open",
                    {}, "y-": "slip", "y+": "slip" }}
  }})", s.length, s.width > 0.0 ? s.width : s.h, s.h, terrain, s.gravity[0], s.gravity[1], s.gravity[2], s.end, s.shape, s.young, s.box,
                                       s.v0, s.mu, s.x_walls);
  return parse_scene(json, "slide");
}

Vec3 centre(const ParticleStore& P) {
  Vec3 c = Vec3::Zero();
  double m = 0.0;
  for (std::size_t p = 0; p < P.size(); ++p) {
    c += P.mass[p] * Vec3(P.x[0][p], P.x[1][p], P.x[2][p]);
    m += P.mass[p];
  }
  return c / m;
}

std::string plane(double theta) {
  return fmt::format(R"({{ "points": [[0, {}], [8, 0]] }})", 8.0 * std::tan(theta));
}

// The 1 m block on the 30-degree terrain plane, one cell across, friction mu, until `end`.
SlideSetup incline_setup(double h, double mu, double end) {
  SlideSetup s;
  s.h = h;
  s.terrain = plane(kTheta);
  s.mu = mu;
  s.end = end;
  s.box = fmt::format(R"("min": [1, 0, 0], "max": [2, {}, 1], "frame": "terrain")", h);
  return s;
}

// Horizontal displacement of the block's centre after `end` on the 30-degree terrain plane.
double incline_travel(double h, double mu, double end, double* normal_drift = nullptr) {
  Solver solver(slide_scene(incline_setup(h, mu, end)));
  const Vec3 c0 = centre(solver.particles());
  while (!solver.finished()) solver.step();
  const Vec3 c1 = centre(solver.particles());
  // the block stays on the plane: its centre moves along the slope
  if (normal_drift) *normal_drift = std::abs((c1 - c0).dot(Vec3(std::sin(kTheta), 0, std::cos(kTheta))));
  return c1[0] - c0[0];
}

// Abe, Johansson & Konagai 2005, eq. 22: x = x0 + g (sin t - mu cos t) cos t t^2 / 2
double rigid_incline(double mu, double t) {
  return kG * (std::sin(kTheta) - mu * std::cos(kTheta)) * std::cos(kTheta) * t * t / 2.0;
}

TEST(TerrainSlide, HorizontalPlaneStoppingDistance) {
  // Abe, Johansson & Konagai 2005, eq. 21: stops at v0^2 / (2 mu g) = 16.99 m after v0 / (mu g) = 3.40 s
  const double rigid = 10.0 * 10.0 / (2.0 * 0.3 * kG);
  // Linear MUSL at h = 0.125 is left out on purpose: at 10 m/s it gains energy from cell crossing
  // (+1.8% by t = 1 s, the same on a flat grid) and slides 5.5% too far; docs/verification.md.
  const std::pair<double, const char*> cases[] = {{0.25, "linear"}, {0.25, "ugimp"}, {0.125, "ugimp"}, {0.125, "bspline2"}};
  for (const auto& [h, shape] : cases) {
    SlideSetup s;
    s.h = h;
    s.shape = shape;
    s.terrain = R"({ "points": [[0, 0], [24, 0]] })";
    s.length = 24.0;
    s.v0 = 10.0;
    s.end = 4.0;
    s.box = fmt::format(R"("min": [1, 0, 0], "max": [2, {}, 1], "frame": "terrain")", h);
    Solver solver(slide_scene(s));
    const double x0 = centre(solver.particles())[0];
    const EnergyBudget e0 = solver.energies();
    while (!solver.finished()) solver.step();
    const double d = centre(solver.particles())[0] - x0;
    const EnergyBudget e1 = solver.energies();
    std::printf("horizontal plane, h = %g, %s: stopping distance %.4f m, rigid %.4f m (%+.2f%%), energy gap %+.2f%%\n",
                h, shape, d, rigid, 100.0 * (d / rigid - 1.0), 100.0 * (e1.total() - e0.total()) / e0.kinetic);
    EXPECT_NEAR(d / rigid, 1.0, 0.02) << "h = " << h << " " << shape;
    // Not a target: measured within 0.01%, so a regression far inside the 2% shows.
    EXPECT_NEAR(d / rigid, 1.0, 0.002) << "h = " << h << " " << shape;
    // the energy budget with friction closes (the kinetic energy went into friction work)
    EXPECT_GT(e1.friction_work, 0.97 * e0.kinetic);
    EXPECT_LT(std::abs(e1.total() - e0.total()), 0.02 * e0.kinetic) << "h = " << h << " " << shape;
  }
}

// A terrain whose profile is flat runs the ProfileTerrain kernels and the bed contact along the
// bed normal; with z_b = 0 and n = e_z they must reproduce the flat grid to the last bit.
TEST(TerrainSlide, FlatProfileReproducesTheFlatGridBitForBit) {
  auto run = [](bool terrain) {
    SlideSetup s;
    s.h = 0.125;
    if (terrain) s.terrain = R"({ "points": [[0, 0], [24, 0]] })";
    s.length = 24.0;
    s.v0 = 10.0;
    s.end = 0.5;
    s.box = terrain ? R"("min": [1, 0, 0], "max": [2, 0.125, 1], "frame": "terrain")"
                    : R"("min": [1, 0, 0], "max": [2, 0.125, 1])";
    Solver solver(slide_scene(s));
    while (!solver.finished()) solver.step();
    return solver;
  };
  const Solver flat = run(false), terrain = run(true);
  const ParticleStore &a = flat.particles(), &b = terrain.particles();
  ASSERT_EQ(a.size(), b.size());
  for (int d = 0; d < 3; ++d) {
    EXPECT_EQ(a.x[d], b.x[d]) << d;
    EXPECT_EQ(a.v[d], b.v[d]) << d;
  }
  for (int c = 0; c < 6; ++c) EXPECT_EQ(a.stress[c], b.stress[c]) << c;
  EXPECT_EQ(flat.energies().friction_work, terrain.energies().friction_work);
}

TEST(TerrainSlide, ThirtyDegreePlaneFromRest) {
  const double rigid = rigid_incline(0.3, 1.5);
  double drift = 0.0;
  const double coarse = incline_travel(0.25, 0.3, 1.5, &drift);
  std::printf("30-degree terrain plane, h = 0.25: travel %.4f m, rigid %.4f m (%+.2f%%), off the plane %.2e m\n",
              coarse, rigid, 100.0 * (coarse / rigid - 1.0), drift);
  EXPECT_NEAR(coarse / rigid, 1.0, 0.02);
  EXPECT_NEAR(coarse / rigid, 1.0, 0.005);  // not a target: measured +0.26%, a regression bound
  EXPECT_LT(drift, 0.1 * 0.25);
}

// Fine: 8 cells per block edge. At E = 1e7 Pa the block barely deforms (static strain 1e-3), so it
// too follows the rigid solution; the paper's fine runs deviate because its block deforms.
TEST(TerrainSlide, ThirtyDegreePlaneFine) {
  const double rigid = rigid_incline(0.3, 1.5);
  const double fine = incline_travel(0.125, 0.3, 1.5);
  std::printf("30-degree terrain plane, h = 0.125: travel %.4f m, rigid %.4f m (%+.2f%%)\n", fine, rigid,
              100.0 * (fine / rigid - 1.0));
  EXPECT_NEAR(fine / rigid, 1.0, 0.05);
  EXPECT_NEAR(fine / rigid, 1.0, 0.005);  // not a target: measured +0.20%, a regression bound
}

TEST(TerrainSlide, SticksWhenFrictionHoldsIt) {
  // tan 30 = 0.577 < mu = 0.7: the block must not slide. Gravity is ramped over 0.5 s: applied at
  // once, the unstressed elastic block bounces on the bed, its normal force swings between about 0
  // and twice the weight, and it creeps down while the force is low (0.12 m over 2 s, measured).
  SlideSetup s;
  s.terrain = plane(kTheta);
  s.mu = 0.7;
  s.end = 2.0;
  Scene scene = slide_scene(s);
  scene.gravity_ramp_time = 0.5;
  Solver solver(scene);
  const double x0 = centre(solver.particles())[0];
  while (!solver.finished()) solver.step();
  const double d = centre(solver.particles())[0] - x0;
  std::printf("30-degree terrain plane, mu = 0.7: horizontal displacement %.3e m over 2 s\n", d);
  EXPECT_LT(std::abs(d), 0.1 * s.h);
}

TEST(TerrainSlide, FlatGridWithRotatedGravityAgrees) {
  const double terrain = incline_travel(0.25, 0.3, 1.5);
  SlideSetup s;
  s.gravity = Vec3(kG * std::sin(kTheta), 0.0, -kG * std::cos(kTheta));
  s.box = R"("min": [1, 0, 0], "max": [2, 0.25, 1])";
  Solver solver(slide_scene(s));
  const double x0 = centre(solver.particles())[0];
  while (!solver.finished()) solver.step();
  const double along = centre(solver.particles())[0] - x0;
  const double flat = along * std::cos(kTheta);  // horizontal component of the down-slope travel
  std::printf("30-degree plane: terrain grid %.4f m, flat grid with rotated gravity %.4f m (%+.2f%%)\n", terrain,
              flat, 100.0 * (terrain / flat - 1.0));
  EXPECT_NEAR(terrain / flat, 1.0, 0.02);
  EXPECT_NEAR(terrain / flat, 1.0, 0.002);  // not a target: measured -0.02%, a regression bound
}

// Near the sliding threshold (docs/verification.md "Near the sliding threshold"): with gravity ramped
// linearly to g over T, a rigid block with tan theta > mu slides from t = 0 at a(t) = g(t) (sin - mu cos),
// so after the ramp s = a ((t - T/2)^2 / 2 + T^2 / 24) along the slope. The friction coefficient with
// which the rigid block would travel as far as the elastic one, minus mu: the figure of merit, since near
// the threshold a(mu) is small and 0.01 in mu is 37% of it at mu = 0.55.
double effective_friction_error(double h, double mu) {
  const double ramp = 0.5, end = 2.0;
  Scene scene = slide_scene(incline_setup(h, mu, end));
  scene.gravity_ramp_time = ramp;
  Solver solver(scene);
  const double x0 = centre(solver.particles())[0];
  while (!solver.finished()) solver.step();
  const double along = (centre(solver.particles())[0] - x0) / std::cos(kTheta);
  const double a = along / ((end - ramp / 2) * (end - ramp / 2) / 2 + ramp * ramp / 24);
  const double mu_eff = std::tan(kTheta) - a / (kG * std::cos(kTheta));
  const double rigid = kG * (std::sin(kTheta) - mu * std::cos(kTheta)) *
                       ((end - ramp / 2) * (end - ramp / 2) / 2 + ramp * ramp / 24);
  std::printf("30-degree terrain plane, mu = %.2f, h = %.3f, gravity ramped over %.1f s: travel along the slope "
              "%.4f m, rigid %.4f m (%+.1f%%): effective mu %.4f (%+.4f)\n",
              mu, h, ramp, along, rigid, 100.0 * (along / rigid - 1.0), mu_eff, mu_eff - mu);
  return mu_eff - mu;
}

// The elastic block slides further than the rigid one when mu is high: at mu = 0.55 its effective
// friction is 0.0068 lower at h = 0.25 (+25% travel), and the deficit grows as the grid is refined
// (0.020 at h = 0.125, 0.046 at 0.0625, 0.21 at 0.03125; measured, not tests). At mu = 0.45 it is
// 1.5e-4. Bounds: the measured values, not targets (the deficit is not explained away: docs/verification.md).
TEST(TerrainSlide, NearTheSlidingThresholdTheFrictionDeficitIsBounded) {
  const double low = effective_friction_error(0.25, 0.45);
  EXPECT_LT(std::abs(low), 1.0e-3);   // measured -1.5e-4
  const double near = effective_friction_error(0.25, 0.55);
  EXPECT_LT(std::abs(near), 0.01);    // measured -0.0068 (courant 0.2-0.35: -0.0057 to -0.0070)
}

}  // namespace
}  // namespace terrain_slide_test
}  // namespace talus

namespace talus {
namespace terrain_slide_test {
namespace {

// The flume in miniature: a 30-degree slope into a flat runout through a circular transition of
// radius 2 m; the block slides down, crosses the transition and stops on the runout.
Scene transition_scene(const std::string& shape, double radius) {
  SlideSetup s;
  s.shape = shape;
  s.length = 16.0;
  s.end = 4.5;
  s.terrain = fmt::format(R"({{ "points": [[0, {}], [6, 0], [16, 0]], "radii": [0, {}, 0] }})", 6.0 * std::tan(kTheta),
                          radius);
  s.box = R"("min": [0.5, 0, 0], "max": [1.5, 0.25, 1], "frame": "terrain")";
  return slide_scene(s);
}

TEST(TerrainSlide, BlockCrossesTheTransitionWithoutJumpsOrSinking) {
  for (const char* shape : {"linear", "ugimp", "bspline2"}) {
    Solver solver(transition_scene(shape, 2.0));
    const TerrainProfile profile(solver.scene().grid.terrain);
    const EnergyBudget e0 = solver.energies();
    double particle_mass = 0.0;
    for (double m : solver.particles().mass) particle_mass += m;
    double released = 0.0, gap = 0.0, jump = 0.0, previous = e0.total(), lowest = 1e30, mass_error = 0.0;
    while (!solver.finished()) {
      solver.step();
      const EnergyBudget e = solver.energies();
      released = std::max(released, e0.gravity - e.gravity);
      gap = std::max(gap, std::abs(e.total() - e0.total()));
      jump = std::max(jump, std::abs(e.total() - previous));
      previous = e.total();
      const ParticleStore& P = solver.particles();
      for (std::size_t p = 0; p < P.size(); ++p) {
        // above the grid's bed (w > 0) and above the profile itself (the chords of the concave
        // transition lie above it)
        const double above = std::min(solver.grid().w_of(P.x[0][p], P.x[2][p]), P.x[2][p] - profile.height(P.x[0][p]));
        lowest = std::min(lowest, above);
      }
      // the nodes receive all the mass through the mapped shape functions (partition of unity)
      const Grid& g = solver.grid();
      double node_mass = 0.0;
      for (std::uint32_t t : g.active_tiles())
        for (int slot = 0; slot < kTileNodes; ++slot) node_mass += g.mass[t * kTileNodes + slot];
      mass_error = std::max(mass_error, std::abs(node_mass - particle_mass) / particle_mass);
    }
    const double x_end = centre(solver.particles())[0];
    std::printf("transition r = 2 m, %s: stops at x = %.3f m; energy gap <= %.2f%% of the %.0f J released, largest "
                "one-step change %.1e; lowest particle %.4f m above the bed\n",
                shape, x_end, 100.0 * gap / released, released, jump / released, lowest);
    EXPECT_GT(x_end, 7.0) << shape;  // it crossed the transition (which ends at x = 6.54 m)
    EXPECT_LT(solver.energies().kinetic, 0.01 * released) << shape;  // and stopped
    EXPECT_LT(gap, 0.02 * released) << shape;      // the budget with friction closes throughout
    EXPECT_LT(jump, 1e-3 * released) << shape;     // no jumps
    EXPECT_GT(lowest, 0.0) << shape;               // no particle below the bed
    EXPECT_LT(mass_error, 1e-12) << shape;
  }
}

using test::same_bits;

// A 3D block on the transition, many colour blocks and re-sorts: bit-identical for 1 and 2 threads.
// An elastic block that fills a trench between two slip x walls on the 30-degree bed settles. The
// bed's normal leans along x: at the nodes where the bed meets an x wall, removing the bed's normal
// velocity after the wall's put an x velocity back into the wall, and the block was squeezed ever
// harder (strain energy 4.7 J after 0.5 s, 26 J after 1 s, 144 J after 2 s). Now it sloshes with a
// bounded strain energy (1.3 J on the terrain grid; at most 0.60 J for the same block on a flat grid
// with rotated gravity, whose sloshing decays while this one's does not).
TEST(TerrainSlide, ABlockBetweenSlipWallsOnASlopeStaysBounded) {
  SlideSetup s;
  s.terrain = plane(kTheta);
  s.length = 1.0;
  s.box = R"("min": [0, 0, 0], "max": [1, 0.25, 1], "frame": "terrain")";
  s.x_walls = R"("x-": "slip", "x+": "slip")";
  s.end = 1.0;
  Solver solver(slide_scene(s));
  double most = 0.0;
  while (!solver.finished()) {
    solver.step();
    most = std::max(most, solver.energies().strain);
  }
  EXPECT_LT(most, 3.0);  // measured 1.3 J
  // (The friction ledger ends at -0.39 J here, -0.47 J before the corner booked its friction on the
  // final velocity. It is booked at the three inner bed columns, which stick in 93% of their contact
  // steps: there the friction impulse is the static reaction and the start velocity it is booked at
  // (-J_t . v_start) no slip but a residue that follows the load's fluctuation with a factor of about
  // -0.17, so each step books about -0.14 m dt^2 |a'_t|^2: -0.16 J at half the time step, -0.054 J
  // at a quarter. Under FLIP the booking is also what the impulse gives the particles (to first order
  // sum_p m_p v_p . N dv = m dv . v_start), so it feeds the sloshing: over 4 s its K + S + G rises by
  // 0.19 J (and by 0.17 J at half the step; at a quarter it decays). docs/theory.md, "Negative
  // friction work where the bed sticks".)
  std::printf("trench: friction work %.4g J, most strain energy %.4g J\n", solver.energies().friction_work, most);
  const ParticleStore& P = solver.particles();
  for (std::size_t p = 0; p < P.size(); ++p) ASSERT_LE(P.x[0][p], 1.0) << p;  // none pressed into the x+ wall
}

TEST(TerrainSlide, BitIdenticalForOneAndTwoThreadsOnATerrainGrid) {
  for (const char* shape : {"bspline2", "cpgimp"}) {
    auto run = [&](int threads) {
      omp_set_num_threads(threads);
      SlideSetup s;
      s.h = 0.1;
      s.shape = shape;
      s.length = 10.0;
      s.end = 0.25;
      s.young = 1.0e6;
      s.terrain = fmt::format(R"({{ "points": [[0, {}], [6, 0], [16, 0]], "radii": [0, 2, 0] }})", 6.0 * std::tan(kTheta));
      s.box = R"("min": [4.0, 0, 0], "max": [5.5, 0.6, 0.6], "frame": "terrain")";
      s.width = 0.8;  // the block 0.6 m wide: a 3D body with a free side
      Scene scene = slide_scene(s);
      scene.bodies[0].velocity = Vec3(3.0, 0.5, -1.7);
      scene.walls[1][0] = scene.walls[1][1] = WallSpec{WallType::Friction, 0.3};
      Solver solver(scene);
      while (!solver.finished()) solver.step();
      EXPECT_GT(solver.sort_count(), 1);
      return solver;
    };
    const auto [one, two] = test::run_on_one_and_two_threads(run);
    test::expect_same_particles_and_energies(one, two, shape);
    EXPECT_GT(one.particles().size(), 4000u);
  }
}

// Restart on a terrain grid: the saved sort cells are (x, y, w) cells; restore maps their centres
// back to z, and the run continues bit for bit.
TEST(TerrainSlide, RestoreOnATerrainGridContinuesBitForBit) {
  Scene scene = transition_scene("ugimp", 2.0);
  scene.end_time = 0.3;
  Solver reference(scene);
  for (int i = 0; i < 150; ++i) reference.step();
  const ParticleStore saved = reference.particles();
  const SolverState state = reference.state();
  while (!reference.finished()) reference.step();
  Solver restored(scene);
  restored.restore(saved, state);
  while (!restored.finished()) restored.step();
  for (int d = 0; d < 3; ++d) {
    EXPECT_TRUE(same_bits(reference.particles().x[d], restored.particles().x[d])) << d;
    EXPECT_TRUE(same_bits(reference.particles().v[d], restored.particles().v[d])) << d;
  }
}

}  // namespace
}  // namespace terrain_slide_test
}  // namespace talus
