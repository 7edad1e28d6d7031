// Periodic boundaries (issue 21, item 3; docs/theory.md "Periodic boundaries"): particles and grid
// nodes wrap at "periodic" x and y faces for every shape function, the cell sort and the colouring
// stay race-free across the seam, and results do not depend on the thread count.
#include "bit_identity.hpp"
#include "scene_fixtures.hpp"
#include "talus/solver/solver.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <map>
#include <string>
#include <vector>

namespace talus {
namespace periodic_test {
namespace {

const char* const kShapes[] = {"linear", "ugimp", "cpgimp", "bspline2"};

// An elastic layer that fills a periodic 1 m x 1 m box, moving at 1 m/s along x or y. Every number
// is dyadic and c + |v| = 3 + 1 m/s (E = 9 rho, nu = 0), so dt = 0.5 h / 4 = 2^-6 s: the particles
// sit on dyadic positions, every weight and nodal sum is exact, and after 1 s (64 steps) each
// particle has crossed the seam once and must be back where it started, to the last bit.
Scene translating_layer(const std::string& shape, const std::string& velocity) {
  return parse_scene(fmt::format(R"({{
    "name": "periodic_layer",
    "grid": {{ "origin": [0, 0, 0], "size": [1.0, 1.0, 0.25], "cell_size": 0.125 }},
    "gravity": [0, 0, 0],
    "time": {{ "end": 1.0, "courant": 0.5 }},
    "solver": {{ "shape": "{}" }},
    "materials": {{ "m": {{ "model": "linear_elastic", "density": 1024.0, "young": 9216.0, "poisson": 0.0 }} }},
    "bodies": [ {{ "name": "layer", "material": "m", "box": {{ "min": [0, 0, 0], "max": [1, 1, 0.25] }},
                  "particles_per_cell": 1, "velocity": {} }} ],
    "boundaries": {{ "x-": "periodic", "x+": "periodic", "y-": "periodic", "y+": "periodic",
                     "z-": "slip", "z+": "slip" }}
  }})", shape, velocity), "translating_layer");
}

std::map<std::int64_t, std::array<double, 6>> by_id(const ParticleStore& P) {
  std::map<std::int64_t, std::array<double, 6>> out;
  for (std::size_t p = 0; p < P.size(); ++p)
    out[P.id[p]] = {P.x[0][p], P.x[1][p], P.x[2][p], P.v[0][p], P.v[1][p], P.v[2][p]};
  return out;
}

TEST(Periodic, LayerTranslatesOnePeriodAndReturnsBitExactly) {
  for (const char* shape : kShapes)
    for (const char* velocity : {"[1, 0, 0]", "[0, 1, 0]"}) {
      SCOPED_TRACE(std::string(shape) + " v = " + velocity);
      Solver solver(translating_layer(shape, velocity));
      const auto start = by_id(solver.particles());
      const EnergyBudget e0 = solver.energies();
      bool wrapped = false;
      while (!solver.finished()) {
        solver.step();
        if (solver.step_count() == 32) {  // half way: every particle moved half a period
          const auto half = by_id(solver.particles());
          const int axis = velocity[1] == '1' ? 0 : 1;
          for (const auto& [id, s] : start) {
            const double expected = s[axis] < 0.5 ? s[axis] + 0.5 : s[axis] - 0.5;
            ASSERT_EQ(half.at(id)[axis], expected) << "particle " << id;
            wrapped = wrapped || s[axis] >= 0.5;
          }
        }
      }
      EXPECT_TRUE(wrapped);
      EXPECT_EQ(solver.step_count(), 64);
      const auto end = by_id(solver.particles());
      ASSERT_EQ(end.size(), start.size());
      // uGIMP and cpGIMP take their domain from cbrt(V0), whose rounding leaves stresses of 1e-13 Pa
      // and velocities of 1e-32 m/s: for them the velocities agree to 1e-20 m/s, the positions exactly
      const bool exact = std::string(shape) == "linear" || std::string(shape) == "bspline2";
      for (const auto& [id, s] : start) {
        for (int c = 0; c < 3; ++c) ASSERT_EQ(end.at(id)[c], s[c]) << "particle " << id << " component " << c;
        for (int c = 3; c < 6; ++c) {
          if (exact) ASSERT_EQ(end.at(id)[c], s[c]) << "particle " << id << " component " << c;
          else ASSERT_NEAR(end.at(id)[c], s[c], 1e-20) << "particle " << id << " component " << c;
        }
      }
      const EnergyBudget e = solver.energies();
      if (exact) EXPECT_EQ(e.kinetic, e0.kinetic);  // momentum and kinetic energy conserved exactly
      else EXPECT_NEAR(e.kinetic, e0.kinetic, 1e-15 * e0.kinetic);
      EXPECT_LT(e.strain, 1e-12 * e0.kinetic);
    }
}

// A compact elastic block crosses the x seam: it must move as the same block on a grid twice as
// long without the seam (slip walls far away), up to the round-off of the shifted positions.
Scene crossing_block(const std::string& shape, bool periodic) {
  return parse_scene(fmt::format(R"({{
    "name": "crossing_block",
    "grid": {{ "origin": [0, 0, 0], "size": [{}, 0.5, 0.5], "cell_size": 0.0625 }},
    "gravity": [0, 0, -9.81],
    "time": {{ "end": 0.35, "courant": 0.4 }},
    "solver": {{ "shape": "{}" }},
    "materials": {{ "m": {{ "model": "linear_elastic", "density": 1000.0, "young": 2.0e5, "poisson": 0.25 }} }},
    "bodies": [ {{ "name": "block", "material": "m", "box": {{ "min": [0.625, 0.1875, 0.0], "max": [0.875, 0.3125, 0.25] }},
                  "particles_per_cell": 2, "velocity": [1.0, 0.3, 0.0] }} ],
    "boundaries": {{ "x-": "{}", "x+": "{}", "y-": "periodic", "y+": "periodic",
                     "z-": {{ "type": "friction", "friction_coefficient": 0.3 }}, "z+": "open" }}
  }})", periodic ? 1.0 : 2.0, shape, periodic ? "periodic" : "slip", periodic ? "periodic" : "slip"), "crossing_block");
}

TEST(Periodic, BlockCrossingTheSeamMovesAsOnAGridWithoutIt) {
  for (const char* shape : kShapes) {
    SCOPED_TRACE(shape);
    Solver wrapped(crossing_block(shape, true)), open(crossing_block(shape, false));
    while (!wrapped.finished()) wrapped.step();
    while (!open.finished()) open.step();
    ASSERT_EQ(wrapped.step_count(), open.step_count());
    const auto a = by_id(wrapped.particles()), b = by_id(open.particles());
    ASSERT_EQ(a.size(), b.size());
    int across = 0;
    double max_dx = 0.0, max_dv = 0.0;
    for (const auto& [id, s] : b) {
      const auto& w = a.at(id);
      const double unwrapped = s[0] >= 1.0 ? s[0] - 1.0 : s[0];
      across += s[0] >= 1.0;
      ASSERT_GE(w[0], 0.0);
      ASSERT_LT(w[0], 1.0);
      max_dx = std::max(max_dx, std::abs(w[0] - unwrapped));
      for (int c = 1; c < 3; ++c) max_dx = std::max(max_dx, std::abs(w[c] - s[c]));
      for (int c = 3; c < 6; ++c) max_dv = std::max(max_dv, std::abs(w[c] - s[c]));
    }
    EXPECT_GE(across, static_cast<int>(a.size()) / 8);  // a good part of the block is past the seam
    EXPECT_LT(max_dx, 1e-12);
    EXPECT_LT(max_dv, 1e-9);
    const EnergyBudget ea = wrapped.energies(), eb = open.energies();
    EXPECT_NEAR(ea.kinetic, eb.kinetic, 1e-9 * eb.kinetic);
    EXPECT_NEAR(ea.strain, eb.strain, 1e-6 * eb.strain);
    EXPECT_NEAR(ea.friction_work, eb.friction_work, 1e-9 * eb.kinetic);
  }
}

// A μ(I) layer on a rough (fixed) floor with gravity tilted along x (the inclined flow of
// docs/mu-i.md), periodic in x and y.
Scene inclined_layer(const std::string& shape, double end_time, int cells_x = 5, int cells_y = 5,
                     int particles_per_cell = 2) {
  const double theta = 24.0 * M_PI / 180.0, g = 9.81;
  return parse_scene(fmt::format(R"({{
    "name": "inclined_layer",
    "grid": {{ "origin": [0, 0, 0], "size": [{}, {}, 0.012], "cell_size": 0.001 }},
    "gravity": [{}, 0, {}],
    "time": {{ "end": {}, "courant": 0.4 }},
    "solver": {{ "shape": "{}", "block_cells": 5 }},
    "materials": {{ "beads": {{ "model": "mu_i", "density": 1470.0, "young": 2.0e5, "poisson": 0.3 }} }},
    "bodies": [ {{ "name": "layer", "material": "beads", "box": {{ "min": [0, 0, 0], "max": [{}, {}, 0.008] }},
                  "particles_per_cell": {}, "velocity": [0.05, 0, 0] }} ],
    "boundaries": {{ "x-": "periodic", "x+": "periodic", "y-": "periodic", "y+": "periodic",
                     "z-": "fixed", "z+": "open" }}
  }})", cells_x * 0.001, cells_y * 0.001, g * std::sin(theta), -g * std::cos(theta), end_time, shape,
                                 cells_x * 0.001, cells_y * 0.001, particles_per_cell), "inclined_layer");
}

TEST(Periodic, ResultsAreBitIdenticalForOneAndTwoThreads) {
  for (const char* shape : kShapes) {
    SCOPED_TRACE(shape);
    // 20 x 10 cells: 4 x 2 colour blocks of 5 cells along the periodic axes, so the blocks of one
    // colour meet across the seam and two threads share them
    const Scene scene = inclined_layer(shape, 0.002, 20, 10, 1);
    auto [one, two] = test::run_on_one_and_two_threads([&](int threads) { return test::run_to_end(scene, threads); });
    test::expect_same_particles_and_energies(one, two, shape);
  }
}

TEST(Periodic, InclinedFlowIsTheSameAtEveryXAndTheBudgetCloses) {
  // The particles of one layer (one z) see the same flow wherever they are along x and y: the
  // periodic faces leave no trace. The wrap shifts of the gravitational term keep the budget closed
  // while the layer flows along the tilted gravity across the seam.
  Solver solver(inclined_layer("linear", 0.05));
  const EnergyBudget e0 = solver.energies();
  while (!solver.finished()) solver.step();
  const ParticleStore& P = solver.particles();
  // group by layer: the particles sit at z = (k + 1/2) 0.5 mm, and the layer compacts by far less
  // than a quarter of that
  std::map<long, std::vector<std::size_t>> layers;
  for (std::size_t p = 0; p < P.size(); ++p) layers[static_cast<long>(std::floor(P.x[2][p] / 0.0005))].push_back(p);
  double max_u = 0.0, max_spread = 0.0;
  for (const auto& [z, members] : layers) {
    double lo = 1e300, hi = -1e300;
    for (std::size_t p : members) {
      lo = std::min(lo, P.v[0][p]);
      hi = std::max(hi, P.v[0][p]);
      max_u = std::max(max_u, P.v[0][p]);
    }
    max_spread = std::max(max_spread, hi - lo);
  }
  std::printf("[ measured ] inclined layer: surface %.4f m/s, largest spread of u within one layer %.2e m/s\n", max_u,
              max_spread);
  EXPECT_GT(max_u, 0.05);  // it flows (from 0.05 m/s at the start)
  EXPECT_LT(max_spread, 1e-9 * max_u);
  const EnergyBudget e = solver.energies();
  const double released = e0.gravity - e.gravity;
  EXPECT_GT(released, 0.0);
  std::printf("[ measured ] inclined layer: budget error %+.2e of the released energy\n", (e.total() - e0.total()) / released);
  EXPECT_LT(std::abs(e.total() - e0.total()), 0.02 * released);
}

}  // namespace
}  // namespace periodic_test
}  // namespace talus
