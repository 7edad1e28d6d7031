// μ(I) granular material in the MPM solver (issue 21): a plane-strain column collapse with the
// glass beads of Jop et al. 2006 runs with an energy budget that closes (the μ(I) dissipation is
// counted as plastic work), the separation rule acts, and results do not depend on the thread count.
#include "bit_identity.hpp"
#include "scene_fixtures.hpp"
#include "talus/solver/solver.hpp"

#include <gtest/gtest.h>
#include <omp.h>

#include <algorithm>
#include <cmath>
#include <string>
#include <vector>

namespace talus {
namespace mu_i_collapse_test {
namespace {

Scene mu_i_column_scene(double cell, double end_time, const char* extra_material_keys = "") {
  const std::string json = fmt::format(R"({{
    "name": "mu_i_column",
    "grid": {{ "origin": [0, 0, 0], "size": [0.6, {}, 0.3], "cell_size": {} }},
    "time": {{ "end": {}, "courant": 0.3 }},
    "materials": {{ "beads": {{ "model": "mu_i", "density": 1500.0, "young": 2.0e6, "poisson": 0.3{} }} }},
    "bodies": [ {{ "name": "column", "material": "beads", "box": {{ "min": [0, 0, 0], "max": [0.1, {}, 0.2] }},
                  "particles_per_cell": 2 }} ],
    "boundaries": {{ "x-": "slip", "x+": "slip", "y-": "slip", "y+": "slip",
                     "z-": {{ "type": "friction", "friction_coefficient": 0.5 }}, "z+": "open" }}
  }})", cell, cell, end_time, extra_material_keys, cell);
  return parse_scene(json, "mu_i_column_scene");
}

TEST(MuICollapse, ColumnSpreadsAndTheEnergyBudgetCloses) {
  // Cell 0.01 m: the budget error is first order in the cell (measured -1.6% at 0.02 m, -0.81% at
  // 0.01 m: the explicit step's work on particles that flow or lose contact), so 0.02 m sits too
  // near the 2% bound.
  Solver solver(mu_i_column_scene(0.01, 0.6));
  ASSERT_TRUE(solver.particles().has_plastic_state());
  EXPECT_FALSE(solver.particles().has_back_stress());
  const EnergyBudget e0 = solver.energies();
  double max_budget_error = 0.0, signed_error = 0.0;
  EnergyBudget e = e0;
  while (!solver.finished()) {
    solver.step();
    if (solver.step_count() % 50 == 0 || solver.finished()) {
      e = solver.energies();
      if (std::abs(e.total() - e0.total()) > max_budget_error) signed_error = e.total() - e0.total();
      max_budget_error = std::max(max_budget_error, std::abs(e.total() - e0.total()));
    }
  }
  const double released = e0.gravity - e.gravity;
  ASSERT_GT(released, 0.0);
  std::printf("[ measured ] mu(I) collapse: budget error %+.2e of the released energy at worst, plastic work %.3f, "
              "friction %.3f, kinetic %.3f of it\n",
              signed_error / released, e.plastic_work / released, e.friction_work / released, e.kinetic / released);
  EXPECT_LT(max_budget_error / released, 0.02);
  EXPECT_GT(e.plastic_work, 0.3 * released);  // μ(I) flow, not the floor, dissipates most
  const ParticleStore& P = solver.particles();
  double front = 0.0, top = 0.0, plastic = 0.0;
  for (std::size_t p = 0; p < P.size(); ++p) {
    for (int d = 0; d < 3; ++d) ASSERT_TRUE(std::isfinite(P.x[d][p]) && std::isfinite(P.v[d][p]));
    for (int c = 0; c < 6; ++c) ASSERT_TRUE(std::isfinite(P.stress[c][p]));
    ASSERT_GE(P.x[2][p], -1e-9);
    front = std::max(front, P.x[0][p]);
    top = std::max(top, P.x[2][p]);
    plastic = std::max(plastic, P.plastic_strain[p]);
  }
  EXPECT_GT(front, 0.15);
  EXPECT_LT(top, 0.17);
  EXPECT_GT(plastic, 0.1);  // the accumulated plastic shear strain
}

TEST(MuICollapse, SeparatedParticlesAreStressFree) {
  Solver solver(mu_i_column_scene(0.02, 0.3, R"(, "separation_volume_ratio": 1.0001)"));
  while (!solver.finished()) solver.step();
  const ParticleStore& P = solver.particles();
  std::size_t separated = 0;
  for (std::size_t p = 0; p < P.size(); ++p)
    if (P.volume[p] > 1.0001 * P.volume0[p]) {
      ++separated;
      for (int c = 0; c < 6; ++c) ASSERT_EQ(P.stress[c][p], 0.0) << "particle " << P.id[p];
      ASSERT_EQ(P.plastic_strain[p], 0.0);
    }
  EXPECT_GT(separated, 0u);
}

// The 0.995 mass quantile of x (equal particle masses): the front of the deposit.
double front_quantile_x(const ParticleStore& P) {
  std::vector<double> x(P.x[0].begin(), P.x[0].begin() + static_cast<std::ptrdiff_t>(P.size()));
  std::sort(x.begin(), x.end());
  return x[static_cast<std::size_t>(std::ceil(0.995 * static_cast<double>(x.size()))) - 1];
}

TEST(MuICollapse, RateIndependentLimitRunsOutLikeDruckerPragerWithTheSameFriction) {
  // With mu_2 -> mu_s the rate dependence vanishes and mu(I) is a perfectly plastic cone sqrt(J2) = mu_s p
  // with isochoric flow: the Drucker-Prager plane-strain cone with 3 alpha = mu_s, psi = 0, c = 0
  // (docs/drucker-prager.md sec. 2: alpha = tan(phi) / sqrt(9 + 12 tan^2 phi)). The two must run the
  // column out alike; a mistake in either model's measure of the shear stress (|s| against sqrt(J2), a
  // factor sqrt(2)) or of the pressure would move the runout by far more than the 1% asserted (measured
  // 0.25% at cell 0.02 m: the flows differ at round-off and the collapse amplifies it).
  const double mu_s = 0.38186;
  const double tan_phi = mu_s / std::sqrt(1.0 - 4.0 / 3.0 * mu_s * mu_s);  // inverts 3 alpha = mu_s
  const double phi_degrees = std::atan(tan_phi) * 180.0 / M_PI;
  Solver mu_i(mu_i_column_scene(0.02, 0.6, R"(, "mu_s": 0.38186, "mu_2": 0.3818604)"));
  const std::string dp_json = fmt::format(R"({{
    "name": "dp_column",
    "grid": {{ "origin": [0, 0, 0], "size": [0.6, 0.02, 0.3], "cell_size": 0.02 }},
    "time": {{ "end": 0.6, "courant": 0.3 }},
    "materials": {{ "sand": {{ "model": "drucker_prager", "density": 1500.0, "young": 2.0e6, "poisson": 0.3,
                             "friction_angle": {:.17g}, "dilatancy_angle": 0.0, "cohesion": 0.0,
                             "cone": "plane_strain" }} }},
    "bodies": [ {{ "name": "column", "material": "sand", "box": {{ "min": [0, 0, 0], "max": [0.1, 0.02, 0.2] }},
                  "particles_per_cell": 2 }} ],
    "boundaries": {{ "x-": "slip", "x+": "slip", "y-": "slip", "y+": "slip",
                     "z-": {{ "type": "friction", "friction_coefficient": 0.5 }}, "z+": "open" }}
  }})", phi_degrees);
  Solver dp(parse_scene(dp_json, "dp_column"));
  while (!mu_i.finished()) mu_i.step();
  while (!dp.finished()) dp.step();
  const double runout_mu_i = front_quantile_x(mu_i.particles()) - 0.1;
  const double runout_dp = front_quantile_x(dp.particles()) - 0.1;
  std::printf("[ measured ] runout from the column's edge: mu(I) with mu_2 -> mu_s %.4f m, Drucker-Prager phi = %.3f deg "
              "%.4f m\n", runout_mu_i, phi_degrees, runout_dp);
  EXPECT_GT(runout_dp, 0.2);  // the column has collapsed (a = 2: about 4 L0 with this low friction)
  EXPECT_NEAR(runout_mu_i, runout_dp, 0.01 * runout_dp);
}

TEST(MuICollapse, BitIdenticalForOneAndTwoThreads) {
  const auto [one, two] = test::run_on_one_and_two_threads([](int threads) {
    omp_set_num_threads(threads);
    Solver solver(mu_i_column_scene(0.02, 0.05));
    while (!solver.finished()) solver.step();
    return solver;
  });
  test::expect_same_particles_and_energies(one, two, "mu(I) collapse");
  EXPECT_TRUE(test::same_bits(one.particles().plastic_strain, two.particles().plastic_strain));
  EXPECT_GT(one.energies().plastic_work, 0.0);
}

}  // namespace
}  // namespace mu_i_collapse_test
}  // namespace talus
