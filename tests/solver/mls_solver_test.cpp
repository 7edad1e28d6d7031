// MLS smoothing in the solver (Edo & Matsubara 2015, eq. 54): scene options, the off path, which particles are
// smoothed, and determinism of whole runs.
#include "bit_identity.hpp"
#include "scene_fixtures.hpp"
#include "talus/core/error.hpp"
#include "talus/scene/scene_json.hpp"
#include "talus/solver/solver.hpp"

#include <gtest/gtest.h>
#include <omp.h>

#include <algorithm>
#include <cmath>
#include <map>


namespace talus {
namespace mls_solver_test {
namespace {

const char* kScene = R"({
  "grid": { "size": [1, 1, 1], "cell_size": 0.1 },
  "time": { "end": 0.1 },
  "solver": { "smoothing": { "basis": "quadratic", "radius_factor": 2.5, "axes": "xz", "bodies": ["b"] } },
  "materials": { "m": { "density": 1000, "young": 1e6, "poisson": 0.3 } },
  "bodies": [ { "name": "a", "material": "m", "box": { "min": [0.2, 0.2, 0.2], "max": [0.4, 0.4, 0.4] } },
              { "name": "b", "material": "m", "box": { "min": [0.5, 0.5, 0.5], "max": [0.7, 0.7, 0.7] } } ]
})";

using test::replace_once;

// This file's messages are checked without their exit code.

TEST(MlsScene, OptionsAreReadResolvedAndEchoed) {
  const Scene s = parse_scene(kScene, "t");
  EXPECT_TRUE(s.smoothing.enabled);
  EXPECT_EQ(s.smoothing.mls.basis, MlsBasis::Quadratic);
  EXPECT_DOUBLE_EQ(s.smoothing.mls.radius_factor, 2.5);
  EXPECT_EQ(s.smoothing.mls.axes, (std::array<bool, 3>{true, false, true}));
  EXPECT_EQ(s.smoothing.bodies, std::vector<int>{1});
  const nlohmann::json echo = scene_to_json(s);
  EXPECT_EQ(echo["solver"]["smoothing"]["basis"], "quadratic");
  EXPECT_EQ(echo["solver"]["smoothing"]["axes"], "xz");
  EXPECT_EQ(echo["solver"]["smoothing"]["bodies"], nlohmann::json::array({"b"}));
  EXPECT_DOUBLE_EQ(echo["solver"]["smoothing"]["min_rcond"].get<double>(), 1e-10);
  const Scene again = parse_scene(echo.dump(), "again");
  EXPECT_EQ(scene_to_json(again), echo);
  // Defaults: no smoothing object = off; an empty one = on, linear, radius 2 cells, all bodies.
  const Scene off = parse_scene(replace_once(kScene, R"("solver": { "smoothing": { "basis": "quadratic", "radius_factor": 2.5, "axes": "xz", "bodies": ["b"] } },)", ""), "t");
  EXPECT_FALSE(off.smoothing.enabled);
  const Scene on = parse_scene(replace_once(kScene, R"({ "basis": "quadratic", "radius_factor": 2.5, "axes": "xz", "bodies": ["b"] })", "{}"), "t");
  EXPECT_TRUE(on.smoothing.enabled);
  EXPECT_EQ(on.smoothing.mls.basis, MlsBasis::Linear);
  EXPECT_DOUBLE_EQ(on.smoothing.mls.radius_factor, 2.0);
  EXPECT_TRUE(on.smoothing.bodies.empty());
  EXPECT_EQ(scene_to_json(on)["solver"]["smoothing"]["bodies"], nlohmann::json::array({"a", "b"}));
}

TEST(MlsScene, BadOptionsNameTheKeyAndTheRange) {
  const std::string ok = kScene;
  test::expect_variant_error(ok, "\"quadratic\"", "\"quartic\"", "solver.smoothing.basis = \"quartic\" is not one of: linear, quadratic, cubic", std::nullopt);
  test::expect_variant_error(ok, "2.5", "0.2", "solver.smoothing.radius_factor = 0.2 is outside the allowed range [0.5, 8]", std::nullopt);
  test::expect_variant_error(ok, "\"xz\"", "\"w\"", "solver.smoothing.axes = \"w\" is not one of: xyz", std::nullopt);
  test::expect_variant_error(ok, "[\"b\"]", "[\"c\"]", "solver.smoothing.bodies[0] = \"c\" names no body (defined: a, b)", std::nullopt);
  test::expect_variant_error(ok, "[\"b\"]", "[\"b\", \"b\"]", "solver.smoothing.bodies[1] = \"b\" is named twice", std::nullopt);
  test::expect_variant_error(ok, "[\"b\"]", "[]", "solver.smoothing.bodies must be a non-empty array", std::nullopt);
  test::expect_variant_error(ok, "\"basis\"", "\"enabled\": 1, \"basis\"", "solver.smoothing.enabled must be true or false", std::nullopt);
  test::expect_variant_error(ok, "\"basis\"", "\"radius\": 1, \"basis\"", "unknown key solver.smoothing.radius", std::nullopt);
  test::expect_variant_error(ok, "\"basis\"", "\"min_rcond\": 0, \"basis\"", "solver.smoothing.min_rcond = 0 is outside the allowed range (0, 1)", std::nullopt);
}

using test::same_bits;

// "enabled": false must be the unsmoothed solver exactly: no smoother, no buffers, same bits.
TEST(MlsSolver, DisabledSmoothingIsTheUnsmoothedSolverBitForBit) {
  Scene plain = test::tumbling_block_scene(0.005);
  Scene disabled = plain;
  disabled.smoothing.enabled = false;
  disabled.smoothing.mls.basis = MlsBasis::Cubic;
  Solver a(plain), b(disabled);
  while (!a.finished()) a.step();
  while (!b.finished()) b.step();
  EXPECT_EQ(b.smoother(), nullptr);
  EXPECT_EQ(b.phase_times()[Phase::Smooth], 0.0);
  for (int c = 0; c < 6; ++c) EXPECT_TRUE(same_bits(a.particles().stress[c], b.particles().stress[c]));
  // And enabling it changes the stresses (the smoother is really in the step).
  Scene smoothed = plain;
  smoothed.smoothing.enabled = true;
  Solver s(smoothed);
  while (!s.finished()) s.step();
  ASSERT_NE(s.smoother(), nullptr);
  EXPECT_GT(s.phase_times()[Phase::Smooth], 0.0);
  EXPECT_FALSE(same_bits(a.particles().stress[0], s.particles().stress[0]));
}

// With MLS the solver sorts again once some particle may have moved a quarter of a cell since the
// last sort (the search walks radius + drift until then), besides the block slack and
// sort_interval; the one-fit-per-cell variant sorts every step.
TEST(MlsSolver, SortsAgainWhenTheDriftPassesAQuarterCell) {
  Scene scene = test::tumbling_block_scene(0.005);
  scene.smoothing.enabled = true;
  scene.sort_interval = 1000;  // only the drift and the slack decide
  Solver s(scene);
  int drift_sorts = 0, steps = 0;
  while (!s.finished()) {
    const SolverState before = s.state();
    const std::int64_t sorts = s.sort_count();
    s.step();
    ++steps;
    const bool drifted = before.sort_drift > 0.25 * scene.grid.h;
    EXPECT_EQ(s.sort_count() - sorts, drifted || before.needs_sort ? 1 : 0) << "step " << steps;
    drift_sorts += drifted && !before.needs_sort ? 1 : 0;
    // the drift is at least this step's largest move: a bound, summed since the sort
    EXPECT_GT(s.state().sort_drift, 0.0);
  }
  EXPECT_GE(drift_sorts, 2);  // the drift, not the slack, asked for sorts
  EXPECT_LT(s.sort_count(), steps / 2);
  scene.smoothing.mls.variant = MlsVariant::Cell;
  Solver cell(scene);
  while (!cell.finished()) cell.step();
  EXPECT_EQ(cell.sort_count(), cell.step_count() + 1);  // at construction and every step
}

// Only the named bodies are smoothed; the others follow the unsmoothed solver bit for bit (the
// bodies never share a node here, and the time step is set by the stiff body b, not smoothed). Both
// runs sort every step (sort_interval = 1; smoothing alone would sort less often), so the
// order of the P2G sums matches (with the frictional floor's stick/slip switch, a round-off
// difference in that order grows to 1e-3 of the stress within this run).
TEST(MlsSolver, UnselectedBodiesAreNotSmoothed) {
  // Both bodies start on the frictional floor moving down into it, two cells apart: they strain at
  // once and never share a node.
  Scene plain = test::tumbling_block_scene(0.01);
  for (BodySpec& b : plain.bodies) {
    b.box_max[2] -= b.box_min[2];
    b.box_min[2] = 0.0;
  }
  plain.bodies[0].velocity = Vec3(0.0, 0.0, -2.0);
  plain.bodies[1].velocity = Vec3(0.0, 0.0, -1.0);
  plain.sort_interval = 1;
  Scene only_a = plain;
  only_a.smoothing.enabled = true;
  only_a.smoothing.bodies = {0};
  Solver a(plain), s(only_a);
  while (!a.finished()) a.step();
  while (!s.finished()) s.step();
  std::map<std::int64_t, std::size_t> where;
  for (std::size_t p = 0; p < s.particles().size(); ++p) where[s.particles().id[p]] = p;
  int body1_same = 0, body0_differ = 0, n0 = 0, n1 = 0;
  const auto& A = a.particles();
  const auto& S = s.particles();
  for (std::size_t p = 0; p < A.size(); ++p) {
    const std::size_t q = where.at(A.id[p]);
    bool equal = A.x[0][p] == S.x[0][q];
    for (int c = 0; c < 6; ++c) equal = equal && A.stress[c][p] == S.stress[c][q];
    if (A.body[p] == 0) {
      ++n0;
      body0_differ += !equal;
    } else {
      ++n1;
      body1_same += equal;
    }
  }
  EXPECT_EQ(a.last_dt(), s.last_dt());
  EXPECT_EQ(body1_same, n1);
  EXPECT_GT(body0_differ, n0 / 2);
  EXPECT_EQ(s.last_smoothing().smoothed + s.last_smoothing().unsmoothed, std::size_t(n0));
}

TEST(MlsSolver, BitIdenticalForOneAndTwoThreads) {
  for (MlsBasis basis : {MlsBasis::Linear, MlsBasis::Quadratic}) {
    auto run = [&](int threads) {
      omp_set_num_threads(threads);
      Scene scene = test::tumbling_block_scene(0.003);
      scene.smoothing.enabled = true;
      scene.smoothing.mls.basis = basis;
      scene.smoothing.mls.radius_factor = 1.2;
      scene.scheme = basis == MlsBasis::Linear ? SchemeKind::Musl : SchemeKind::Usavg;
      scene.shape = basis == MlsBasis::Linear ? ShapeKind::Linear : ShapeKind::CpGimp;
      Solver solver(scene);
      while (!solver.finished()) solver.step();
      return solver;
    };
    const auto [one, two] = test::run_on_one_and_two_threads(run);
    test::expect_same_particles_and_energies(one, two, to_string(basis));
    EXPECT_TRUE(same_bits(one.particles().volume, two.particles().volume));
    EXPECT_EQ(one.unsmoothed_total(), two.unsmoothed_total());
    EXPECT_GT(one.smoothing_passes(), 0);
    EXPECT_EQ(one.smoothing_passes(), two.smoothing_passes());
    EXPECT_EQ(one.last_smoothing_change(), two.last_smoothing_change());  // deterministic_sum: fixed chunks
    EXPECT_EQ(one.max_smoothing_change(), two.max_smoothing_change());
    EXPECT_GT(one.max_smoothing_change(), 0.0);
    // the sort is reused between drifts, at the same steps on any thread count
    EXPECT_LT(one.sort_count(), one.step_count());
    EXPECT_EQ(one.sort_count(), two.sort_count());
  }
}

// The `reused` variant with reuse_strain 0 fits at every step that strains the material: the
// particle fit's run bit for bit (its fits keep weights, which change no result). With a larger
// reuse_strain it fits less often, and stays the same for any thread count.
TEST(MlsSolver, ReusedWeightsAtZeroStrainAreTheParticleFitAndDeterministic) {
  Scene particle = test::tumbling_block_scene(0.03);
  particle.smoothing.enabled = true;
  particle.smoothing.mls.radius_factor = 1.2;
  Scene every = particle;
  every.smoothing.mls.variant = MlsVariant::Reused;
  every.smoothing.mls.reuse_strain = 0.0;
  Solver a(particle), b(every);
  while (!a.finished()) a.step();
  while (!b.finished()) b.step();
  test::expect_same_particles_and_energies(a, b, "reuse_strain 0");
  EXPECT_EQ(b.smoothing_fits(), b.smoothing_passes());
  EXPECT_GT(b.mls_weight_bytes(), 0u);
  EXPECT_EQ(a.mls_weight_bytes(), 0u);

  auto run = [&](int threads) {
    omp_set_num_threads(threads);
    Scene scene = every;
    scene.smoothing.mls.reuse_strain = 0.02;
    scene.sort_interval = 3;  // the weights follow the particles through sorts
    Solver solver(scene);
    int carried = 0;  // steps that sorted and then reused the weights
    while (!solver.finished()) {
      const std::int64_t sorts = solver.sort_count(), fits = solver.smoothing_fits();
      solver.step();
      carried += solver.sort_count() > sorts && solver.smoothing_fits() == fits ? 1 : 0;
    }
    EXPECT_GT(carried, 0);
    return solver;
  };
  const auto [one, two] = test::run_on_one_and_two_threads(run);
  test::expect_same_particles_and_energies(one, two, "reused");
  EXPECT_EQ(one.smoothing_fits(), two.smoothing_fits());
  EXPECT_GT(one.smoothing_fits(), 1);
  EXPECT_LT(one.smoothing_fits(), one.smoothing_passes());
  EXPECT_FALSE(same_bits(one.particles().stress[0], a.particles().stress[0]));  // reusing changes the run
}

TEST(MlsScene, ReusedVariantAndItsStrain) {
  const Scene s = parse_scene(replace_once(kScene, R"("axes": "xz")", R"("axes": "xz", "variant": "reused", "reuse_strain": 0.01)"), "t");
  EXPECT_EQ(s.smoothing.mls.variant, MlsVariant::Reused);
  EXPECT_DOUBLE_EQ(s.smoothing.mls.reuse_strain, 0.01);
  EXPECT_EQ(scene_to_json(s)["solver"]["smoothing"]["variant"], "reused");
  test::expect_variant_error(kScene, "\"axes\"", "\"reuse_strain\": 2, \"axes\"",
                             "solver.smoothing.reuse_strain = 2 is outside the allowed range [0, 1]", std::nullopt);
}

}  // namespace
}  // namespace mls_solver_test
}  // namespace talus
