#pragma once
// The outputs of a run, one object each. Each knows when it is due (its OutputSchedule, whose next
// time lives in RunProgress and so travels in the checkpoint), how to write, and how to pick up a
// resumed run: a restart cuts every file back to the checkpoint's step before appending.
//
//   EnergyHistory  energy.csv            history schedule (output.history_interval; 0 = every step)
//   RunoutFiles    runout.csv            history schedule; runout.json and deposit.csv at the end
//                                        (only with diagnostics.runout)
//   FrameSeries    frames/*.vtu + .pvd   frame schedule (output.frame_interval; 0 = first and last);
//                                        a distributed run writes one .vtu piece per rank and a .pvtu
//   CheckpointFile checkpoint.h5         checkpoint schedule (output.checkpoint_interval; 0 = none),
//                                        and on a signal or an instability
// Crash safety (docs/reliability.md): frames, the .pvd index, scene.json and checkpoints are written
// to a temporary name and renamed; history rows are flushed one by one.
#include "talus/core/comm.hpp"
#include "talus/diagnostics/runout.hpp"
#include "talus/io/background_writer.hpp"
#include "talus/io/checkpoint.hpp"
#include "talus/io/vtu_writer.hpp"
#include "talus/solver/solver.hpp"

#include <cmath>
#include <cstdint>
#include <filesystem>
#include <fstream>
#include <optional>
#include <string>
#include <vector>

namespace talus {

/// An output on a time interval. `next` is the time it is next due (kept in RunProgress).
struct OutputSchedule {
  double interval;  // [s]; 0 = not on a schedule
  double& next;
  /// Whether time t has reached the next output time (never when there is no interval).
  bool reached(double t) const { return interval > 0.0 && t >= next; }
  /// Move the next output time past t (an output just written at t). One or two steps of
  /// `interval` do that when the interval is at least the time step. A far smaller one would take
  /// (t - next) / interval steps, and one below t's rounding step none at all (next + interval ==
  /// next): the run hung in this loop. An output is then due at every step anyway, so after a
  /// bounded number of steps the next time becomes the smallest time after t.
  void advance_past(double t) {
    if (interval <= 0.0) return;
    for (int i = 0; i < 64 && next <= t; ++i) next += interval;
    if (next <= t) next = std::nextafter(t, HUGE_VAL);
  }
};

/// Create the output folder. A fresh run removes the outputs of an earlier run there (no stale frame
/// survives); a resumed run keeps the frames `resume` lists (index < resume->frame_times.size(),
/// whether .vtu, .pvtu or a rank's piece) and drops later ones. Both remove leftover temporary files
/// of a killed writer. In a distributed run rank 0 alone creates and deletes; every rank returns
/// once it is done (and throws its error, if it met one).
void prepare_output_folder(const std::filesystem::path& dir, const RunProgress* resume, const Comm& comm = Comm());

/// The files a run writes, replaces or clears at the top of its output folder (the frames aside):
/// what a run's inputs must not be.
std::vector<std::filesystem::path> run_output_files(const std::filesystem::path& dir);

/// Whether two paths name the same file: the same inode when both exist, else the same normalised
/// absolute path (a file the run is yet to create).
bool same_file(const std::filesystem::path& a, const std::filesystem::path& b);

/// energy.csv: time, step, dt, every term of the energy ledger, total; with `gap_terms`
/// (output.energy_gap_terms) then the EnergyGapTerms.
class EnergyHistory {
 public:
  /// A fresh run (no resume_step) starts the file with its header; a resumed one keeps the rows up
  /// to resume_step (the file rewritten atomically) and appends.
  /// In a distributed run only rank 0 writes (`writer`); the others keep no file.
  EnergyHistory(const std::filesystem::path& dir, std::optional<std::int64_t> resume_step, bool writer = true,
                bool gap_terms = false);
  /// One row, flushed: a killed run leaves only whole rows behind. Collective with gap terms (every
  /// rank calls it).
  void write(const Solver& solver, const EnergyBudget& energies);
  void flush() {
    if (writer_) file_.flush();
  }
  /// A resumed history: the rows kept up to the checkpoint's step (0: energy.csv was missing or
  /// unreadable, so the history starts at the restart).
  std::size_t kept_rows() const { return kept_rows_; }

 private:
  bool writer_;
  bool gap_terms_;
  std::size_t kept_rows_ = 0;
  std::ofstream file_;
};

/// runout.csv, runout.json, deposit.csv (docs/flume.md); does nothing without diagnostics.runout.
class RunoutFiles {
 public:
  /// In a distributed run the particles are gathered to rank 0, which measures and writes.
  /// `resume_dir`: the checkpoint's folder when a resumed run writes elsewhere (its runout.csv
  /// holds the rows before the checkpoint, which the monitor continues from); empty: `dir`.
  /// `saved_first_row`: the checkpoint's copy of runout.csv's first row (RunProgress), which
  /// stands for the folder's when they differ or the folder has none.
  RunoutFiles(const Scene& scene, const std::filesystem::path& dir, std::optional<std::int64_t> resume_step,
              const Comm& comm = Comm(), const std::filesystem::path& resume_dir = {},
              const std::string& saved_first_row = {});
  bool enabled() const { return monitor_.has_value(); }
  /// runout.csv's first row as the checkpoint keeps it (empty before the first row, and off rank 0).
  std::string first_row() const;
  /// One row of runout.csv, on the history schedule (collective).
  void write(const Solver& solver);
  /// What finish() wrote: the runout after the last step, and the files' paths.
  struct Outcome {
    std::optional<RunoutResult> result;
    std::string summary_path;  // runout.json
    std::string deposit_path;  // deposit.csv (empty unless the run completed)
  };
  /// runout.json (the front after the last step, with `status`: run.json's completed, interrupted or
  /// unstable), and deposit.csv when the run completed (collective; the outcome is rank 0's).
  Outcome finish(Solver& solver, const std::string& status) const;
  /// runout.json of a distributed run that an instability on this rank ends, from the last row of
  /// runout.csv (the last good state there is: the other ranks may wait in a collective, so nothing
  /// is gathered), with status "unstable". Any rank: write() gives every rank the first and last rows
  /// and the mass gone through open faces at the last. Does nothing before the first row.
  void finish_unstable() const;
  const std::string& history_path() const { return history_path_; }

 private:
  const Scene& scene_;
  std::filesystem::path dir_;
  Comm comm_;
  std::optional<RunoutMonitor> monitor_;
  std::string history_path_;
  std::ofstream file_;
  double left_ = 0.0, left_x_plus_ = 0.0;  // a distributed run: gone through open faces at the last row
};

/// The particle frames and the ParaView series that lists them.
///
/// One rank writes frame i as frames/particles_<i:06>.vtu. In a distributed run each rank writes
/// its own particles as the piece frames/particles_<i:06>_<rank:04>.vtu (a rank may hold none);
/// once all have, rank 0 writes frames/particles_<i:06>.pvtu, which lists the pieces of ranks
/// 0..N-1, and adds it to the .pvd. Only rank 0 writes the .pvd; the others keep its entries.
///
/// Frames are written in the background: write() copies the particle arrays (in parallel) and
/// returns; VTK's compression and the file write run on a thread of their own while the solver
/// steps on, one frame at a time (the next write() waits for the one before). The .pvd lists a
/// frame once its file is on disk: right after the write in a run on one rank; at the next
/// complete() in a distributed run, whose summary waits for every rank's piece.
class FrameSeries {
 public:
  /// `progress` records each frame's time and step (the checkpoint carries them); a resumed run's
  /// series starts with the frames it lists. `comm`: the ranks that hold the particles.
  /// `background` false: every write() is on disk (and listed) when it returns.
  FrameSeries(const std::filesystem::path& dir, bool compress, RunProgress& progress, const Comm& comm,
              bool background = true);
  /// Start writing the solver's particles as the next frame; returns the file name the .pvd lists
  /// (frames/...vtu, or frames/...pvtu in a distributed run). Throws the error of the frame before,
  /// if its write failed. Every rank must call it.
  std::string write(Solver& solver);
  /// Wait until every frame started is on disk and listed in the .pvd; throws a failed write's
  /// error. Collective in a distributed run. Call it before anything that relies on the frames
  /// being on disk: a checkpoint (a resumed run keeps the frames it lists) and the end of the run.
  void complete(Solver& solver);
  /// A distributed run, after each step: once every rank's piece of the frame in flight is on disk,
  /// write its .pvtu and list it (a small collective a step, only while a frame is in flight). So a
  /// run that one rank's instability ends (MPI_Abort) keeps its finished frames in the series.
  void list_finished_frame(Solver& solver);
  /// Whether the last frame is of this step already.
  bool has_frame_of_step(std::int64_t step) const;
  const std::string& pvd_path() const { return pvd_path_; }
  /// The frames the .pvd lists.
  std::size_t listed() const { return pvd_.size(); }
  /// A resumed series whose kept frames hold their stress and strain in the solver's Voigt order
  /// (written by a build before 2026-12-04): the new frames use VTK's order, so the series mixes them.
  bool kept_frames_in_older_order() const { return kept_frames_in_older_order_; }
  /// A resumed series: the frames the checkpoint lists that are found neither here nor in the folder
  /// they were written in (RunProgress::frame_folders; a folder of the run's own with frames
  /// deleted: the series has gaps), and the frames folders they are missing from.
  std::size_t missing_kept_frames() const { return missing_kept_frames_; }
  const std::vector<std::filesystem::path>& missing_from() const { return missing_from_; }
  /// The seconds the writer's thread spent on the frames completed so far, in the background (0
  /// without background writes: the run loop waited for them). The work recorder's run total.
  double background_seconds() const { return background_seconds_; }

 private:
  /// complete() without the phase timer.
  void finish_pending();

  std::filesystem::path dir_;
  bool kept_frames_in_older_order_ = false;
  std::size_t missing_kept_frames_ = 0;
  std::vector<std::filesystem::path> missing_from_;
  bool compress_;
  bool background_;
  RunProgress& progress_;
  Comm comm_;
  std::string pvd_path_;
  PvdIndex pvd_;
  /// A distributed run's frame whose pieces are being written: its summary and .pvd entry are
  /// written once every piece is on disk.
  struct PendingSummary {
    std::size_t index;
    double time;
    const ParticleStore* layout;  // the solver's store: the summary declares its arrays
  };
  std::optional<PendingSummary> pending_summary_;
  double background_seconds_ = 0.0;  // added to by the writer's thread, read after its join
  BackgroundWriter writer_;  // declared last: destroyed (its thread joined) before the members it writes
};

/// checkpoint.h5: the solver's state and the run's progress.
class CheckpointFile {
 public:
  explicit CheckpointFile(const std::filesystem::path& dir) : path_((dir / "checkpoint.h5").string()) {}
  void write(Solver& solver, const RunProgress& progress);
  const std::string& path() const { return path_; }

 private:
  std::string path_;
};

/// The frames a run of `scene` writes from its start by output.frame_interval: the first at t = 0,
/// one each interval, and the last at the end (2 with no interval).
std::size_t frames_by_interval(const Scene& scene);
/// The steps a run of `scene` takes at its initial time step (Scene::initial_time_step), to time.end
/// or time.max_steps: an estimate, short of a flow that speeds up (its step shrinks).
double estimated_steps(const Scene& scene);
/// The frames a run of `scene` writes: frames_by_interval, but at most one a step, so no more than
/// estimated_steps + 1 (then an estimate, not a bound). Fewer when max_steps or an emptied grid ends
/// it early.
std::size_t frames_of_run(const Scene& scene);

/// The folder frame i of a run was written in (RunProgress::frame_folders, relative to the run's
/// folder `dir`); `dir` when the checkpoint does not say.
std::filesystem::path frame_folder(const RunProgress& progress, std::size_t index, const std::filesystem::path& dir);
/// Record that the frames from the next one on are written in `dir`: a fresh run (no resume_dir)
/// writes all of them there; a run resumed from a checkpoint in another folder `resume_dir` keeps
/// the earlier frames' folders, rebased to `dir`. (A run resumed in place keeps the checkpoint's.)
void record_frame_folder(RunProgress& progress, const std::filesystem::path& dir,
                         const std::filesystem::path& resume_dir);

/// The name of frame i: frames/particles_<i:06>.vtu, or, for a distributed run, the summary of its
/// pieces frames/particles_<i:06>.pvtu.
std::string frame_name(std::size_t index, bool distributed = false);
/// The piece of frame i that `rank` writes in a distributed run: frames/particles_<i:06>_<rank:04>.vtu.
std::string frame_piece_name(std::size_t index, int rank);

}  // namespace talus
