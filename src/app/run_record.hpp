#pragma once
// run.json: a run's own record in its output folder. It says which talus ran the scene (the build
// `talus --version` names), how (the command, threads, ranks, vector path, OpenMP settings), where
// (host, CPU), when, and how the run ended:
//   "running"      while it runs (a record that still says so after the process is gone: the run
//                  was killed, or its machine stopped)
//   "completed"    it reached its end time (or every particle left through the open faces)
//   "interrupted"  SIGINT/SIGTERM: it wrote a checkpoint and stopped; the record says how to resume
//   "unstable"     a guard stopped it; the last good state was written as a frame and a checkpoint
//   "failed"       any other error (a full disk, say), with its message
// A run resumed from a checkpoint keeps the records of the parts before it under "earlier_parts".
// scene.json stays the scene alone, so that it can be run again as it is; the record is beside it.
// Written atomically (a temporary file renamed), so a killed run leaves a whole record.
#include "talus/core/comm.hpp"
#include "talus/core/error.hpp"
#include "talus/driver/run_driver.hpp"
#include "talus/solver/solver.hpp"

#include <nlohmann/json.hpp>

#include <chrono>
#include <cstdint>
#include <ctime>
#include <filesystem>
#include <optional>
#include <string>
#include <vector>
#include <string_view>

namespace talus::app {

/// What a run's record knows before the run starts.
struct RunStart {
  std::string scene_path;       // as given on the command line
  std::string restart_path;     // the checkpoint resumed from (empty: a fresh run)
  std::vector<std::string> restart_changes;  // what the scene changed of the checkpoint's (restart_changes)
  std::size_t estimated_bytes;  // the memory estimate of `talus check` (all ranks)
  std::int64_t particles;       // on every rank together
  /// When the command started (before the scene was read and the particles seeded): the record's
  /// "started" and "wall_seconds" count from here, as --stop-after does.
  std::chrono::steady_clock::time_point clock_start;
  std::time_t utc_start;
};

/// What a run's record says of its end beyond the RunSummary (each a collective to count).
struct RunEnd {
  std::int64_t particles;          // on every rank together
  std::int64_t outflow_particles;  // left through the open faces, this run and the parts before it
  OutflowFaces outflow_by_face;    // the same by face, with their mass
};

class RunRecord {
 public:
  /// Builds the record of a run about to start in `dir` and, on the writer (rank 0), writes it with
  /// status "running". A resumed run (start.restart_path) takes the record of the parts before it
  /// from the run.json of the checkpoint's folder. Every rank builds the same record, so that a rank
  /// that fails alone in a distributed run can write how it ended.
  RunRecord(const std::filesystem::path& dir, const Solver& solver, const RunStart& start, const Comm& comm);

  /// While the run goes on (RunOptions::heartbeat): "progress" says the step and time reached and
  /// when. Rank 0 writes; a record it cannot write now is left as it was (the run goes on).
  void progress(const Solver& solver);
  /// Where the energy growth first passed guards.energy_warning_factor (RunOptions::on_energy_warning):
  /// kept for "end", whichever way the run ends (a run that warned and then tripped the energy guard
  /// recorded "unstable" without the warning).
  void energy_warning(const EnergyWarning& warning) { energy_warning_ = warning; }

  /// The end of a run that returned: "completed" or "interrupted", with its results. Rank 0 writes.
  void end(const Solver& solver, const RunSummary& summary, const RunEnd& counts);
  /// The end of a run that an error stopped on this rank: "unstable" (an Instability) or "failed",
  /// with the error's message and what this rank knows. Any rank may write it; one that every rank
  /// threw together (Error::agreed) rank 0 alone writes, without "end.rank" (its message names the rank).
  void end_with_error(const Solver& solver, const Error& error);
  void end_with_error(const Solver& solver, const std::exception& error);

  const nlohmann::ordered_json& json() const { return record_; }

 private:
  void end_common(const Solver& solver, std::string_view status, const std::string& message);
  /// `this_ranks`: the error is this rank's alone ("end.rank" names it), not one every rank threw.
  void end_after_error(const Solver& solver, std::string_view status, const std::string& message, bool this_ranks);
  void write() const;

  std::filesystem::path path_;
  Comm comm_;
  std::chrono::steady_clock::time_point started_;
  nlohmann::ordered_json record_;
  std::optional<EnergyWarning> energy_warning_;
};

}  // namespace talus::app
