// Drucker-Prager sand in the MPM solver (issue 5): a plane-strain column collapse runs to rest
// with an energy budget that closes, and the granular rules (psi -> 0 once flowing, stress-free
// separated particles) act as documented.
#include "scene_fixtures.hpp"
#include "talus/solver/solver.hpp"

#include <gtest/gtest.h>
#include <omp.h>

#include <algorithm>
#include <cmath>
#include <utility>
#include <vector>

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

// The grid's density where the resting deposit is whole: nodal mass (linear weights, summed across the
// one cell in y) over h^3, median over the x-z nodes whose four adjacent cells all hold a particle.
// This is the packing the positions make, whatever the particles' own volumes say
// (tools/separation_study.py measures it the same way).
double interior_packing(const ParticleStore& P, double h) {
  const double reach = 0.7, top = 0.35;  // beyond the deposit of any run here [m]
  const int nx = int(reach / h) + 2, nz = int(top / h) + 2;
  std::vector<double> mass(std::size_t(nx) * nz, 0.0);
  std::vector<char> occupied(std::size_t(nx) * nz, 0);
  for (std::size_t p = 0; p < P.size(); ++p) {
    const double gx = P.x[0][p] / h, gz = P.x[2][p] / h;
    const int i = int(std::floor(gx)), k = int(std::floor(gz));
    if (i < 0 || k < 0 || i + 1 >= nx || k + 1 >= nz) continue;
    const double fx = gx - i, fz = gz - k, m = P.mass[p];
    occupied[std::size_t(i) * nz + k] = 1;
    mass[std::size_t(i) * nz + k] += (1 - fx) * (1 - fz) * m;
    mass[std::size_t(i + 1) * nz + k] += fx * (1 - fz) * m;
    mass[std::size_t(i) * nz + k + 1] += (1 - fx) * fz * m;
    mass[std::size_t(i + 1) * nz + k + 1] += fx * fz * m;
  }
  std::vector<double> interior;
  for (int i = 1; i < nx; ++i)
    for (int k = 1; k < nz; ++k)
      if (occupied[std::size_t(i) * nz + k] && occupied[std::size_t(i - 1) * nz + k] &&
          occupied[std::size_t(i) * nz + k - 1] && occupied[std::size_t(i - 1) * nz + k - 1])
        interior.push_back(mass[std::size_t(i) * nz + k] / (h * h * h));
  EXPECT_GT(interior.size(), 50u);
  std::nth_element(interior.begin(), interior.begin() + interior.size() / 2, interior.end());
  return interior[interior.size() / 2];
}

TEST(GranularCollapse, ColumnDepositRecompactsWithALowSeparationRatio) {
  // The stretching collapse loosens the sand. With the default separation ratio (1.5) loose sand
  // carries stress again below 1.5 V0 and rests loose; with 1.05 it is stress-free until it has
  // compacted to within 5% of its seeded volume (Dunatunga & Kamrin's 2015 disconnected state), so
  // the deposit settles nearer the seeded density, 1600 kg/m^3 (docs/flume.md, "The sand loosens as
  // it flows"). Measured 2026-12-05 at this cell (0.01 m): packing 1379 kg/m^3 with 1.5, 1490 with
  // 1.05; 1456 and 1537 at 0.005 m, so what is left converges with the cell.
  const double h = 0.01, rho0 = 1600.0;
  auto settle = [&](const char* keys) {
    Solver solver(test::column_collapse_scene(h, 0.8, keys));
    while (!solver.finished()) solver.step();
    double volume = 0.0, seeded = 0.0;
    const ParticleStore& P = solver.particles();
    for (std::size_t p = 0; p < P.size(); ++p) {
      volume += P.volume[p];
      seeded += P.volume0[p];
    }
    return std::pair{interior_packing(P, h) / rho0, volume / seeded};
  };
  const auto [packing_default, volume_default] = settle("");
  const auto [packing_low, volume_low] = settle(R"(, "separation_volume_ratio": 1.05)");
  EXPECT_GE(packing_low, 0.90);                     // measured 0.931
  EXPECT_GE(packing_low - packing_default, 0.04);   // measured 0.069
  EXPECT_LT(volume_low, volume_default - 0.05);     // particle volumes: measured 1.135 against 1.251
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
