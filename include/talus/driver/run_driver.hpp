#pragma once
// The run loop: steps the solver to the end time, writes the outputs when each is due
// (driver/run_outputs.hpp: energy history, runout files, frames, checkpoints), keeps the last good
// state for the instability guards, catches SIGINT/SIGTERM/SIGUSR1 and prints a progress line.
//
// Output folder:
//   scene.json           the fully resolved scene (every default filled in)
//   particles.pvd        ParaView time series of the frames
//   frames/particles_NNNNNN.vtu
//   energy.csv           time, step, dt, each term of the energy ledger (solver/energy_budget.hpp), total
//   checkpoint.h5        the last checkpoint (output.checkpoint_interval, SIGINT/SIGTERM/SIGUSR1, instability)
//   runout.csv           runout diagnostics on the history schedule (only with diagnostics.runout)
//   runout.json          the runout after the last step: front, tail, gate, runout plane (diagnostics.runout)
//   deposit.csv          the deposit thickness raster at the end (only with diagnostics.runout)
//   terrain.vtu          the terrain surface, written once (only when the scene has a terrain)
//   run.json             the run's record (written by `talus run`, app/run_record.hpp, not by run_scene)
#include "talus/core/error.hpp"
#include "talus/diagnostics/runout.hpp"
#include "talus/io/checkpoint.hpp"
#include "talus/solver/solver.hpp"
#include "talus/solver/work_recorder.hpp"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <functional>
#include <optional>
#include <string>

namespace talus {

struct RunOptions {
  std::string out_dir;
  bool progress = true;       // print a progress line to stderr
  double progress_seconds = 2.0;  // between progress lines (talus run: 2 on a terminal, 30 into a log; --progress-every)
  /// Called on every rank after a step, at most every progress_seconds (whether or not the line is
  /// printed), and not after the last step: talus run updates its record (run.json) with the step
  /// reached, so that a killed run's record says how far it got.
  std::function<void(const Solver&)> heartbeat;
  /// Called on every rank when the energy growth first passes guards.energy_warning_factor (and at
  /// the start of a run resumed after it did): talus run keeps it in its record, which a run that
  /// then stops on an instability writes without the run's summary.
  std::function<void(const EnergyWarning&)> on_energy_warning;
  /// Continue a run from a checkpoint already restored into the solver (restore_checkpoint): keep
  /// its frames and history up to the checkpoint, drop what came later.
  const RunProgress* resume = nullptr;
  /// The checkpoint's folder, when it is not out_dir (talus run --restart ... --out DIR): the
  /// runout history before the checkpoint stays there, and the runout monitor reads its first and
  /// last rows from it (the initial front is the default gate).
  std::string resume_dir;
  /// The checkpoint file resumed from (talus run --restart FILE). Empty: the folder's own
  /// checkpoint.h5. A run resumed in place from another file (checkpoint_earlier.h5) does not know
  /// what the folder's checkpoint.h5 holds.
  std::string resume_file;
  /// Catch SIGINT/SIGTERM/SIGUSR1: finish the step, write a checkpoint and return (interrupted_signal).
  bool handle_signals = true;
  /// Stop as a signal would (finish the step, write a checkpoint, return with stopped_at_deadline)
  /// after the first step that ends at or past this time (talus run --stop-after: a batch job's
  /// wall-time limit less a margin). In a distributed run every rank stops at the same step.
  std::optional<std::chrono::steady_clock::time_point> deadline;
  /// Work recorder (talus run --record-work): attached to the solver for the run; the time the
  /// loop spends outside a recorded step (output, guards) is added to that step as serial time.
  WorkRecorder* recorder = nullptr;
  /// Write each frame's file on a thread of its own while the steps go on (FrameSeries); false:
  /// every frame is on disk before the next step (talus run --foreground-frames).
  bool frames_in_background = true;
  /// The caller has already called prepare_output_folder (talus run does, before it starts the run,
  /// so that an unusable folder is an error every rank meets alike, said once).
  bool folder_prepared = false;
};

struct RunSummary {
  std::int64_t steps = 0;
  std::int64_t first_step = 0;  // the step this call started from (a resumed run's checkpoint step)
  double time = 0.0;
  double wall_seconds = 0.0;
  double particle_updates = 0.0;     // steps taken by this call times the particles each moved (all ranks)
  std::size_t frames = 0;            // frames written by this call
  std::size_t frames_in_series = 0;  // frames the .pvd lists (a run resumed in its folder: the earlier ones too)
  EnergyBudget initial, final;
  /// The energy the run had to spend by its end (EnergyGuard::available: the initial kinetic and
  /// strain energy plus the most potential energy released, and a floor of M |g| h / 1000); 0 where
  /// run_scene did not set it.
  double energy_available = 0.0;
  /// The scale the budget's gap is measured on: the energy available, which does not depend on where
  /// the grid's origin lies. (Until 2026-12-06 it was the initial total, whose gravity term is measured
  /// from z = 0: the same run lifted by 1000 m closed 3300 times "better".) Without it, the initial
  /// total or, where that is near zero, the sum of the energies it is made of.
  double energy_scale() const {
    if (energy_available > 0.0) return energy_available;
    return std::max({std::abs(initial.total()), initial.kinetic + initial.strain + std::abs(initial.gravity), 1e-300});
  }
  /// The gap in joules: final total - initial total.
  double energy_budget_gap_joules() const { return final.total() - initial.total(); }
  /// How far the budget failed to close: (final total - initial total) / energy_scale().
  double energy_budget_gap() const { return energy_budget_gap_joules() / energy_scale(); }
  EnergyGapTerms final_gap;  // output.energy_gap_terms: at the end (zero when off)
  /// Where the total energy first grew by more than guards.energy_warning_factor times the energy
  /// available (warned about as it happened, or in the part before the checkpoint); absent when it never did.
  std::optional<EnergyWarning> energy_warning;
  std::string pvd_path;
  std::string checkpoint_path;  // <out_dir>/checkpoint.h5
  int interrupted_signal = 0;   // SIGINT/SIGTERM/SIGUSR1 caught: the run stopped after writing a checkpoint
  bool stopped_at_deadline = false;  // RunOptions::deadline passed: the run stopped after writing a checkpoint
  std::optional<RunoutResult> runout;  // with diagnostics.runout: the front after the last step
  std::string runout_path;             // <out_dir>/runout.csv (with diagnostics.runout)
  std::string runout_summary_path;     // <out_dir>/runout.json (with diagnostics.runout)
  std::string deposit_path;            // <out_dir>/deposit.csv (written when the run reached its end)
  std::string terrain_path;            // <out_dir>/terrain.vtu (when the scene has a terrain)
};

/// Prepare `out_dir` (creating it; earlier talus outputs there are replaced, unless resuming) and run
/// to the end. An instability (Error of kind Instability) is rethrown after the last good state has
/// been written as a frame and a checkpoint; its message then says where.
RunSummary run_scene(Solver& solver, const RunOptions& options);

/// The energy guard's instability (guards.energy_growth_factor): a breach of the global energy
/// ledger, which every rank holds alike, so that under mpirun it is said as the job's ("energy guard,
/// all ranks"), not as the rank's that happened to report it (rank 0, which may hold no particle).
class LedgerInstability : public Error {
 public:
  explicit LedgerInstability(const std::string& message) : Error(Kind::Instability, message) {}
};

}  // namespace talus
