#pragma once
// The measures of the papers' elastic benchmarks (docs/verification.md), shared by the tests; the
// sweep driver tools/speed_vs_error.py computes the same numbers from the run outputs.
#include "talus/scene/scene_json.hpp"
#include "talus/solver/solver.hpp"

#include <algorithm>
#include <cmath>
#include <map>
#include <string>
#include <vector>

namespace talus::test {

inline Scene benchmark_scene(const std::string& name, ShapeKind shape, SchemeKind scheme) {
  Scene s = read_scene_file(std::string(TALUS_SOURCE_DIR) + "/inputs/benchmarks/" + name + ".json");
  s.shape = shape;
  s.scheme = scheme;
  return s;
}

inline void run_to_end(Solver& solver) {
  while (!solver.finished()) solver.step();
}

/// Particle stress sigma_xx averaged over the particles of one x-layer (the bar's cross-section),
/// ordered by x: the 1D profile of a thin bar.
struct Profile {
  std::vector<double> x, stress;
};

inline Profile axial_profile(const ParticleStore& P) {
  std::map<long long, std::pair<double, double>> sum;  // key: x rounded to 1e-6 of a cell
  std::map<long long, int> count;
  std::vector<std::size_t> order(P.size());
  for (std::size_t p = 0; p < P.size(); ++p) order[p] = p;
  std::sort(order.begin(), order.end(), [&](std::size_t a, std::size_t b) { return P.x[0][a] < P.x[0][b]; });
  Profile prof;
  // Particles of a layer share x up to round-off (a 1D problem); group runs closer than 1e-6.
  for (std::size_t k = 0; k < order.size();) {
    std::size_t j = k;
    double xs = 0.0, ss = 0.0;
    while (j < order.size() && P.x[0][order[j]] - P.x[0][order[k]] < 1e-6) {
      xs += P.x[0][order[j]];
      ss += P.stress[XX][order[j]];
      ++j;
    }
    prof.x.push_back(xs / double(j - k));
    prof.stress.push_back(ss / double(j - k));
    k = j;
  }
  return prof;
}

/// Bardenhagen-Kober column, Edo & Matsubara 2015, eq. 61-62: sigma(x) = E (sqrt(2 rho0 b (Delta - x)/E + 1) - 1),
/// Delta = L0 + rho0 b L0^2 / (2E).
struct ColumnError {
  double l2 = 0.0;         // || sigma_p - sigma(x_p) || / || sigma(x_p) || over the particles
  double roughness = 0.0;  // RMS of sigma_{k+1} - 2 sigma_k + sigma_{k-1} along the bar, / W
};

inline ColumnError column_error(const Solver& solver, double E, double rho0, double b, double L0) {
  const double delta = L0 + rho0 * b * L0 * L0 / (2 * E);
  const Profile prof = axial_profile(solver.particles());
  double num = 0.0, den = 0.0;
  for (std::size_t k = 0; k < prof.x.size(); ++k) {
    const double x = std::min(prof.x[k], delta);
    const double exact = E * (std::sqrt(2 * rho0 * b * (delta - x) / E + 1) - 1);  // Edo & Matsubara 2015, eq. 61
    num += (prof.stress[k] - exact) * (prof.stress[k] - exact);
    den += exact * exact;
  }
  double rough = 0.0;
  for (std::size_t k = 1; k + 1 < prof.x.size(); ++k) {
    const double d2 = prof.stress[k + 1] - 2 * prof.stress[k] + prof.stress[k - 1];
    rough += d2 * d2;
  }
  ColumnError e;
  e.l2 = std::sqrt(num / den);
  e.roughness = std::sqrt(rough / double(prof.x.size() - 2)) / (rho0 * std::abs(b) * L0);  // b < 0: compression
  return e;
}

}  // namespace talus::test
