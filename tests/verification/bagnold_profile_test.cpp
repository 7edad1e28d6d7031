// Steady inclined flow of a μ(I) layer (issue 21, item 4; docs/mu-i.md sec. 8): a layer of thickness h
// on a rough incline of angle θ, periodic along the slope, reaches the Bagnold profile
//   u(z) = (2/3) (I_θ / d) √(φ g cos θ) (h^{3/2} − (h − z)^{3/2}),  I_θ = I0 (tan θ − μs)/(μ2 − tan θ)
// (GDR MiDi 2004; Jop, Forterre & Pouliquen 2005). CI size: 8 cells over the depth, h = 10 d
// (the full-size input inputs/inclined_flow_bagnold.json has h = 20 d and 16 cells; the profile
// u/u(h) against z/h and the relaxation measured in units of h/u(h) do not depend on h/d).
#include "talus/scene/scene_json.hpp"
#include "talus/solver/solver.hpp"

#include <fmt/core.h>
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <map>
#include <vector>

namespace talus {
namespace bagnold_profile_test {
namespace {

constexpr double kTheta = 24.0 * M_PI / 180.0, kG = 9.81;
constexpr double kMuS = 0.3818628674187188, kMu2 = 0.6434683848584607, kI0 = 0.279;  // glass beads (defaults)
constexpr double kD = 0.53e-3, kRhoS = 2450.0, kRho = 1470.0;                         // φ = 0.6
constexpr double kH = 10 * kD;  // layer thickness
constexpr int kCells = 8;       // cells over the depth

double bagnold(double z) {  // GDR MiDi 2004; Jop et al. 2005
  const double i_theta = kI0 * (std::tan(kTheta) - kMuS) / (kMu2 - std::tan(kTheta));
  const double phi = kRho / kRhoS;
  const double depth = std::max(kH - z, 0.0);
  return 2.0 / 3.0 * i_theta / kD * std::sqrt(phi * kG * std::cos(kTheta)) * (std::pow(kH, 1.5) - std::pow(depth, 1.5));
}

// Periodic along the slope (x, 3 cells: one colour block), one cell across y between slip walls
// (the flow is along x, so they only hold v_y = 0), a fixed floor (no slip: the rough base).
// E = 25 kPa: the base's elastic shear strain μ p / G is 3.2e-3 (docs/mu-i.md sec. 8).
Scene inclined_flow(double end_time) {
  const double cell = kH / kCells;
  return parse_scene(fmt::format(R"({{
    "name": "bagnold_ci",
    "grid": {{ "origin": [0, 0, 0], "size": [{}, {}, {}], "cell_size": {} }},
    "gravity": [{}, 0, {}],
    "time": {{ "end": {}, "courant": 0.4 }},
    "solver": {{ "shape": "linear", "block_cells": 3 }},
    "materials": {{ "beads": {{ "model": "mu_i", "density": {}, "young": 2.5e4, "poisson": 0.3 }} }},
    "bodies": [ {{ "name": "layer", "material": "beads", "box": {{ "min": [0, 0, 0], "max": [{}, {}, {}] }},
                  "particles_per_cell": 2 }} ],
    "boundaries": {{ "x-": "periodic", "x+": "periodic", "y-": "slip", "y+": "slip", "z-": "fixed", "z+": "open" }}
  }})", 3 * cell, cell, kH + 3 * cell, cell, kG * std::sin(kTheta), -kG * std::cos(kTheta), end_time, kRho,
                                 3 * cell, cell, kH), "bagnold_ci");
}

struct Profile {
  std::vector<double> z, u;  // per row of particles, bottom to top
};

Profile rows_of(const ParticleStore& P) {
  std::map<long, std::pair<double, std::vector<double>>> rows;  // by z in quarter cells
  const double quarter = kH / kCells / 4.0;
  for (std::size_t p = 0; p < P.size(); ++p) {
    auto& row = rows[static_cast<long>(std::floor(P.x[2][p] / (2 * quarter)))];
    row.first = P.x[2][p];
    row.second.push_back(P.v[0][p]);
  }
  Profile out;
  for (const auto& [key, row] : rows) {
    double sum = 0.0;
    for (double u : row.second) sum += u;
    out.z.push_back(row.first);
    out.u.push_back(sum / row.second.size());
  }
  return out;
}

TEST(BagnoldProfile, InclinedMuILayerReachesTheBagnoldProfile) {
  const double u_surface = bagnold(kH);                    // 0.1004 m/s
  // The layer starts at rest; its distance from the steady profile decays with an e-folding time
  // of about 15 u(h) / (g cos θ) (measured, docs/mu-i.md sec. 8): 6 of them leave 0.25%.
  const double relax = 15.0 * u_surface / (kG * std::cos(kTheta));  // 0.17 s
  const double end_time = 6.0 * relax;
  Solver solver(inclined_flow(end_time));
  Profile half;
  while (!solver.finished()) {
    solver.step();
    if (half.z.empty() && solver.time() >= 0.8 * end_time) half = rows_of(solver.particles());
  }
  const Profile end = rows_of(solver.particles());
  ASSERT_EQ(end.z.size(), static_cast<std::size_t>(2 * kCells));  // the rows stay rows
  double num = 0.0, den = 0.0, max_u = 0.0;
  for (std::size_t r = 0; r < end.z.size(); ++r) {
    const double a = bagnold(end.z[r]);
    num += (end.u[r] - a) * (end.u[r] - a);
    den += a * a;
    max_u = std::max(max_u, end.u[r]);
  }
  const double l2 = std::sqrt(num / den);
  const double top = end.u.back(), top_analytic = bagnold(end.z.back());
  const double surface_error = top / top_analytic - 1.0;
  const double drift = end.u.back() / half.u.back() - 1.0;  // over the last 20% of the run
  std::printf("[ measured ] Bagnold, %d cells over h: surface row %.4f m/s against %.4f (%+.2f%%), L2 of the profile "
              "%.2f%%, change of the surface over the last 1.2 e-folding times %+.3f%%\n",
              kCells, top, top_analytic, 100.0 * surface_error, 100.0 * l2, 100.0 * drift);
  // At 8 cells over the depth the resolution study measured +2.3% at the surface and 3.9% L2
  // (docs/mu-i.md sec. 8: 16 cells meet the issue's 3% / 5%); the bounds leave room for that
  // discretisation error and no more.
  EXPECT_LT(std::abs(surface_error), 0.035);
  EXPECT_LT(l2, 0.055);
  // steady: the change over the last 1.2 e-folding times is (e^1.2 - 1) = 2.3 times the distance
  // still to go (measured +0.61%: 0.27% to go)
  EXPECT_LT(std::abs(drift), 0.01);
  EXPECT_EQ(max_u, top);              // the fastest row is the surface row
}

}  // namespace
}  // namespace bagnold_profile_test
}  // namespace talus
