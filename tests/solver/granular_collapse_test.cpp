// Drucker-Prager sand in the MPM solver (issue 5): a plane-strain column collapse runs to rest
// with an energy budget that closes, and the granular rules (psi -> 0 once flowing, stress-free
// separated particles) act as documented.
#include "scene_fixtures.hpp"
#include "talus/solver/solver.hpp"

#include <gtest/gtest.h>
#include <omp.h>

#include <algorithm>
#include <cmath>

namespace talus {
namespace granular_collapse_test {
namespace {

TEST(GranularCollapse, ColumnRunsToRestAndTheEnergyBudgetCloses) {
  Solver solver(test::column_collapse_scene(0.01, 0.8));
  const EnergyBudget e0 = solver.energies();
  double max_kinetic = 0.0;
  double max_budget_error = 0.0;
  EnergyBudget e = e0;
  while (!solver.finished()) {
    solver.step();
    if (solver.step_count() % 50 == 0 || solver.finished()) {
      e = solver.energies();
      max_kinetic = std::max(max_kinetic, e.kinetic);
      max_budget_error = std::max(max_budget_error, std::abs(e.total() - e0.total()));
    }
  }
  const double released = e0.gravity - e.gravity;  // potential energy given up by the collapse
  ASSERT_GT(released, 0.0);
  // kinetic + potential + stored elastic + plastic dissipation + floor friction = initial, within
  // 2% of the energy the collapse released (measured 2026-12-05: -1.0% at this size, -0.39% at full
  // size; energy lost, first order in the cell: docs/drucker-prager.md sec. 7).
  EXPECT_LT(max_budget_error / released, 0.02);
  // Plastic flow, not friction on the floor, takes most of the energy (measured 90% / 10%).
  EXPECT_GT(e.plastic_work, 0.5 * released);
  EXPECT_GT(e.friction_work, 0.0);
  // At rest: the kinetic energy has fallen to a few percent of its peak (measured ~1%).
  EXPECT_LT(e.kinetic, 0.05 * max_kinetic);
  const ParticleStore& P = solver.particles();
  double front = 0.0, top = 0.0;
  for (std::size_t p = 0; p < P.size(); ++p) {
    for (int d = 0; d < 3; ++d) ASSERT_TRUE(std::isfinite(P.x[d][p]) && std::isfinite(P.v[d][p]));
    for (int c = 0; c < 6; ++c) ASSERT_TRUE(std::isfinite(P.stress[c][p]));
    ASSERT_GE(P.x[2][p], -1e-9) << "particle " << P.id[p] << " sank below the floor";
    front = std::max(front, P.x[0][p]);
    top = std::max(top, P.x[2][p]);
  }
  // The column (0.1 m wide, 0.2 m high) has spread and lowered.
  EXPECT_GT(front, 0.15);
  EXPECT_LT(top, 0.17);
}

TEST(GranularCollapse, PlasticStateExistsOnlyWithDruckerPrager) {
  Solver elastic(test::free_fall_scene("musl"));
  EXPECT_FALSE(elastic.particles().has_plastic_state());
  EXPECT_TRUE(elastic.particles().plastic_strain.empty());
  Solver sand(test::column_collapse_scene(0.02, 0.01));
  EXPECT_TRUE(sand.particles().has_plastic_state());
  EXPECT_EQ(sand.particles().plastic_strain.size(), sand.particles().size());
  // perfect plasticity (H = 0): the back stress would stay zero, so it is not allocated
  EXPECT_FALSE(sand.particles().has_back_stress());
  EXPECT_TRUE(sand.particles().back_stress[0].empty());
  Solver hardening(test::column_collapse_scene(0.02, 0.01, R"(, "hardening_modulus": 1.0e5, "kinematic_fraction": 0.2)"));
  EXPECT_TRUE(hardening.particles().has_back_stress());
  EXPECT_EQ(hardening.particles().back_stress[5].size(), hardening.particles().size());
}

TEST(GranularCollapse, SeparatedParticlesAreStressFreeAndVirgin) {
  // A separation ratio just above 1 declares every dilating particle separated; the collapse
  // dilates the sand near the free surface, so some particles must end stress-free.
  Solver solver(test::column_collapse_scene(0.02, 0.3, R"(, "separation_volume_ratio": 1.0001)"));
  while (!solver.finished()) solver.step();
  const ParticleStore& P = solver.particles();
  std::size_t separated = 0;
  for (std::size_t p = 0; p < P.size(); ++p) {
    if (P.volume[p] > 1.0001 * P.volume0[p]) {
      // The rule runs after the volume update of the step, so this particle was declared
      // separated in the last step: stress exactly zero, plastic state reset.
      ++separated;
      for (int c = 0; c < 6; ++c) ASSERT_EQ(P.stress[c][p], 0.0) << "particle " << P.id[p];
      ASSERT_EQ(P.plastic_strain[p], 0.0);
    }
  }
  EXPECT_GT(separated, 0u);
}

TEST(GranularCollapse, BitIdenticalForOneAndTwoThreads) {
  struct Result {
    ParticleStore particles;
    EnergyBudget energies;
  };
  auto run = [](int threads) {
    omp_set_num_threads(threads);
    Solver solver(test::column_collapse_scene(0.02, 0.05));
    while (!solver.finished()) solver.step();
    return Result{solver.particles(), solver.energies()};
  };
  const Result a = run(1);
  const Result b = run(2);
  const ParticleStore& A = a.particles;
  const ParticleStore& B = b.particles;
  ASSERT_EQ(A.size(), B.size());
  for (std::size_t p = 0; p < A.size(); ++p) {
    for (int c = 0; c < 6; ++c) ASSERT_EQ(A.stress[c][p], B.stress[c][p]);
    ASSERT_EQ(A.plastic_strain[p], B.plastic_strain[p]);
    ASSERT_EQ(A.x[0][p], B.x[0][p]);
  }
  EXPECT_EQ(a.energies.plastic_work, b.energies.plastic_work);
}

}  // namespace
}  // namespace granular_collapse_test
}  // namespace talus
