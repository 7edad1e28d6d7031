#pragma once
// The run loop with its outputs: steps the solver to the end time, writes particle frames on the
// frame schedule, energy-history rows on the history schedule, and a progress line.
//
// Output folder:
//   scene.json           the fully resolved scene (every default filled in)
//   particles.pvd        ParaView time series of the frames
//   frames/particles_NNNNNN.vtu
//   energy.csv           time, step, dt, kinetic, strain, gravity, boundary_work, plastic_work, total
#include "talus/solver/solver.hpp"

#include <string>

namespace talus {

struct RunOptions {
  std::string out_dir;
  bool progress = true;       // print a progress line to stderr
  double progress_seconds = 2.0;
};

struct RunSummary {
  std::int64_t steps = 0;
  double time = 0.0;
  double wall_seconds = 0.0;
  std::size_t frames = 0;
  EnergyBudget initial, final;
  std::string pvd_path;
};

/// Prepare `out_dir` (creating it; earlier talus outputs there are replaced) and run to the end.
RunSummary run_scene(Solver& solver, const RunOptions& options);

}  // namespace talus
