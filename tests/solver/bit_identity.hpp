#pragma once
// Checks shared by the solver tests that two runs agree to the last bit (thread counts, restarts).
#include "talus/solver/solver.hpp"

#include <gtest/gtest.h>
#include <omp.h>

#include <cstring>
#include <span>
#include <string>
#include <utility>
#include <vector>

namespace talus::test {

/// Bit-for-bit equality of two arrays. memcmp on an empty vector's null data() is undefined
/// behaviour (UBSan), so sizes are compared first.
inline bool same_bits(std::span<const double> x, std::span<const double> y) {
  return x.size() == y.size() && (x.empty() || std::memcmp(x.data(), y.data(), x.size() * sizeof(double)) == 0);
}

/// The solvers that run(1) and run(2) return, made on one thread and then on two; the thread
/// count is restored afterwards. For the tests that results do not depend on the thread count.
template <class Run>
std::pair<Solver, Solver> run_on_one_and_two_threads(const Run& run) {
  const int saved = omp_get_max_threads();
  Solver one = run(1);
  Solver two = run(2);
  omp_set_num_threads(saved);
  return {std::move(one), std::move(two)};
}

/// Runs `scene` to its end on `threads` threads, after prepare(solver) (a block order, say), and
/// restores the caller's thread count.
template <class Prepare>
Solver run_to_end(const Scene& scene, int threads, Prepare prepare) {
  const int saved = omp_get_max_threads();
  omp_set_num_threads(threads);
  Solver solver(scene);
  prepare(solver);
  while (!solver.finished()) solver.step();
  omp_set_num_threads(saved);
  return solver;
}
inline Solver run_to_end(const Scene& scene, int threads) {
  return run_to_end(scene, threads, [](Solver&) {});
}

/// Expects two finished runs to hold the same particles (ids, positions, velocities, stresses)
/// and the same energy budget to the last bit; `label` names the case in a failure message.
inline void expect_same_particles_and_energies(const Solver& one, const Solver& two, const std::string& label = "") {
  const ParticleStore& a = one.particles();
  const ParticleStore& b = two.particles();
  ASSERT_EQ(a.size(), b.size()) << label;
  EXPECT_EQ(a.id, b.id) << label;
  for (int d = 0; d < 3; ++d) {
    EXPECT_TRUE(same_bits(a.x[d], b.x[d])) << label << " position " << d;
    EXPECT_TRUE(same_bits(a.v[d], b.v[d])) << label << " velocity " << d;
  }
  for (int c = 0; c < 6; ++c) EXPECT_TRUE(same_bits(a.stress[c], b.stress[c])) << label << " stress " << c;
  const EnergyBudget ea = one.energies(), eb = two.energies();
  EXPECT_EQ(std::memcmp(&ea, &eb, sizeof(EnergyBudget)), 0) << label;
  const EnergyGapTerms ga = one.energy_gap_terms(), gb = two.energy_gap_terms();
  if (one.scene().output.energy_gap_terms == two.scene().output.energy_gap_terms) {
    EXPECT_EQ(std::memcmp(&ga, &gb, sizeof(EnergyGapTerms)), 0) << label << " gap terms";
  }
}

}  // namespace talus::test
