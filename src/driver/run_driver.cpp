#include "talus/driver/run_driver.hpp"

#include "talus/core/error.hpp"
#include "talus/diagnostics/runout.hpp"
#include "talus/driver/run_outputs.hpp"
#include "talus/driver/warning.hpp"
#include "talus/io/runout_output.hpp"
#include "talus/io/atomic_file.hpp"
#include "talus/io/vtu_writer.hpp"
#include "talus/particles/particle_migration.hpp"
#include "talus/scene/scene_json.hpp"
#include "talus/solver/dilation_check.hpp"
#include "talus/solver/stability_guards.hpp"

#include <fmt/core.h>
#include <unistd.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <csignal>
#include <cstdio>

namespace talus {

namespace fs = std::filesystem;

namespace {

volatile std::sig_atomic_t g_signal = 0;

extern "C" void on_stop_signal(int sig) { g_signal = sig; }

/// SIGINT/SIGTERM set a flag for the run loop while this lives; a second signal acts as usual
/// (SA_RESETHAND), so a run that does not stop can still be killed. SIGUSR1 too: Open MPI's mpirun
/// forwards it to every rank (a SIGTERM to mpirun kills the ranks a second later, before a large
/// checkpoint is written), and batch systems send it ahead of a time limit (Slurm's --signal).
class SignalCatcher {
 public:
  explicit SignalCatcher(bool enabled) : enabled_(enabled) {
    if (!enabled_) return;
    g_signal = 0;
    struct sigaction sa {};
    sa.sa_handler = on_stop_signal;
    sigemptyset(&sa.sa_mask);
    sa.sa_flags = SA_RESETHAND;
    sigaction(SIGINT, &sa, &old_int_);
    sigaction(SIGTERM, &sa, &old_term_);
    sigaction(SIGUSR1, &sa, &old_usr1_);
  }
  ~SignalCatcher() {
    if (!enabled_) return;
    sigaction(SIGINT, &old_int_, nullptr);
    sigaction(SIGTERM, &old_term_, nullptr);
    sigaction(SIGUSR1, &old_usr1_, nullptr);
  }
  SignalCatcher(const SignalCatcher&) = delete;
  SignalCatcher& operator=(const SignalCatcher&) = delete;
  int caught() const { return enabled_ ? static_cast<int>(g_signal) : 0; }

 private:
  bool enabled_;
  struct sigaction old_int_ {}, old_term_ {}, old_usr1_ {};
};

std::string format_duration(double seconds) {
  if (!std::isfinite(seconds) || seconds < 0) return "?";
  const long s = std::lround(seconds);
  if (s >= 3600) return fmt::format("{}h{:02}m", s / 3600, (s / 60) % 60);
  if (s >= 60) return fmt::format("{}m{:02}s", s / 60, s % 60);
  return fmt::format("{}s", s);
}

/// The progress line on stderr: at most every `seconds`, and after the last step.
class ProgressLine {
 public:
  ProgressLine(const Solver& solver, const RunOptions& options)
      : solver_(solver), enabled_(options.progress && solver.comm().root()), seconds_(options.progress_seconds),
        first_step_(solver.step_count()), first_fraction_(done_fraction()), start_(std::chrono::steady_clock::now()),
        last_(start_), tty_(isatty(fileno(stderr))) {}

  double elapsed() const { return std::chrono::duration<double>(std::chrono::steady_clock::now() - start_).count(); }

  /// The particles on every rank (a distributed run's rate counts them all); set at the start.
  void set_particles(std::int64_t n) { particles_ = n; }

  void update() {
    const auto now = std::chrono::steady_clock::now();
    const bool last = solver_.finished();
    if (!enabled_ || (std::chrono::duration<double>(now - last_).count() < seconds_ && !last)) return;
    last_ = now;
    const Scene& scene = solver_.scene();
    const double wall = elapsed();
    const double fraction = done_fraction();
    const double rate = (solver_.step_count() - first_step_) * double(particles_) / std::max(wall, 1e-9);
    // The time left at the pace of this process: a resumed run's wall clock counts from its restart,
    // so it is set against the share done since then (against the whole share, a run resumed at 90%
    // said a tenth of the time it had left).
    const double eta = wall * (1.0 - fraction) / std::max(fraction - first_fraction_, 1e-12);
    fmt::print(stderr, "{}talus: step {:>8}  t = {:.4g}/{:.4g} s ({:5.1f}%)  dt = {:.3e} s  {:.2f} M particle-updates/s  ETA {}{}",
               tty_ ? "\r" : "", solver_.step_count(), solver_.time(), scene.end_time, 100.0 * fraction, solver_.last_dt(),
               rate / 1e6, format_duration(eta), tty_ ? "   " : "\n");
    if (tty_ && last) fmt::print(stderr, "\n");
  }

 private:
  /// The share of the run done: of its end time, or of its step limit where that comes first.
  double done_fraction() const {
    const Scene& scene = solver_.scene();
    const double of_time = solver_.time() / scene.end_time;
    return scene.max_steps > 0 ? std::max(of_time, double(solver_.step_count()) / scene.max_steps) : of_time;
  }

  const Solver& solver_;
  bool enabled_;
  double seconds_;
  std::int64_t first_step_;
  double first_fraction_;
  std::int64_t particles_ = static_cast<std::int64_t>(solver_.particles().size());
  std::chrono::steady_clock::time_point start_, last_;
  bool tty_;
};

/// A thread count beyond any node's, for the regions the history row opens on many threads (the
/// runout's sort then cuts as many chunks as its length allows).
constexpr int kManyThreads = 1 << 16;

/// With a work recorder (talus run --record-work): the solver's steps timed apart from the rest of
/// the loop (outputs, guards, snapshot), which is added to each recorded step as serial time, and
/// both totals over the run for the model's run prediction (solver/work_recorder.hpp).
class LoopRecording {
 public:
  LoopRecording(Solver& solver, WorkRecorder* recorder)
      : solver_(solver), recorder_(recorder), first_step_(solver.step_count()) {
    solver_.record_work(recorder_);
  }
  ~LoopRecording() {
    if (recorder_) solver_.record_work(nullptr);
  }
  LoopRecording(const LoopRecording&) = delete;
  LoopRecording& operator=(const LoopRecording&) = delete;

  void step_begins() {
    if (!recorder_) return;
    step_start_ = step_end_ = Clock::now();
  }
  void step_done() {
    if (recorder_) step_end_ = Clock::now();
  }
  /// The parallel parts of the loop's work after a step, each timed apart from the serial rest
  /// (output, guards): the snapshot (the field check before it, one parallel scan per particle
  /// array, and the parallel copies of the particles and the sort state), and the history row (the
  /// energies, one parallel sum, and the runout's parallel loops and sort; its file writes ride along).
  enum class Part { Snapshot, History };
  /// Runs f() as a `part` of `regions` parallel regions; returns what f returns (false: not done,
  /// and not counted).
  template <class F>
  bool parallel_part(Part part, F&& f, int regions) {
    if (!recorder_) return f();
    const Clock::time_point start = Clock::now();
    const bool done = f();
    if (!done) return false;
    const double s = seconds(start, Clock::now());
    PartTimes& t = part == Part::Snapshot ? snapshot_ : history_;
    t.step_seconds += s;
    t.step_regions += regions;
    t.seconds += s;
    t.regions += regions;
    return true;
  }
  /// The loop's work after the step (outputs, guards, snapshot) is done.
  void loop_done() {
    if (!recorder_) return;
    solver_seconds_ += seconds(step_start_, step_end_);
    if (recorder_->last_step_recorded()) {
      const double loop = seconds(step_end_, Clock::now());
      const std::size_t particles = solver_.particles().size();
      if (snapshot_.step_regions > 0)
        recorder_->add_after_step("snapshot", snapshot_.step_seconds, particles, snapshot_.step_regions);
      if (history_.step_regions > 0)
        recorder_->add_after_step("history row", history_.step_seconds, particles, history_.step_regions);
      recorder_->add_after_step("output and guards", loop - snapshot_.step_seconds - history_.step_seconds);
    }
    for (PartTimes* t : {&snapshot_, &history_}) {
      t->step_seconds = 0.0;
      t->step_regions = 0;
    }
  }
  /// `background_seconds`: the frames' writes on the writer's thread, beside the steps.
  void finish(double wall_seconds, double background_seconds) {
    if (recorder_)
      recorder_->set_totals({.steps = solver_.step_count() - first_step_,
                             .solver_seconds = solver_seconds_,
                             .other_seconds = wall_seconds - solver_seconds_,
                             .snapshot_seconds = snapshot_.seconds,
                             .snapshot_regions = snapshot_.regions,
                             .history_seconds = history_.seconds,
                             .history_regions = history_.regions,
                             .background_seconds = background_seconds});
  }

 private:
  using Clock = std::chrono::steady_clock;
  static double seconds(Clock::time_point a, Clock::time_point b) { return std::chrono::duration<double>(b - a).count(); }

  Solver& solver_;
  WorkRecorder* recorder_;
  std::int64_t first_step_;
  Clock::time_point step_start_, step_end_;
  double solver_seconds_ = 0.0;
  struct PartTimes {
    double seconds = 0.0, step_seconds = 0.0;  // the run's, and the current step's
    std::int64_t regions = 0;
    int step_regions = 0;
  };
  PartTimes snapshot_, history_;
};

/// The last state that passed every guard, kept in memory to be written when a later step fails.
struct Snapshot {
  bool valid = false;
  ParticleStore particles;
  SolverState state;
  RunProgress progress;
  std::int64_t step = -1;
};

/// One run: its outputs, schedules, guards and snapshot, and the loop over steps.
class RunLoop {
 public:
  RunLoop(Solver& solver, const RunOptions& options)
      : solver_(solver), scene_(solver.scene()), comm_(solver.comm()), dir_(options.out_dir),
        resuming_(options.resume != nullptr),
        resumed_in_place_(resuming_ && (options.resume_dir.empty() || same_file(options.resume_dir, options.out_dir))),
        progress_(resuming_ ? *options.resume : RunProgress{}), resume_dir_(options.resume_dir),
        resume_file_(options.resume_file),
        history_(dir_, resume_step(), comm_.root(), scene_.output.energy_gap_terms), runout_(scene_, dir_, resume_step(), comm_, options.resume_dir, progress_.runout_first_row),
        frames_(dir_, scene_.output.compress, progress_, comm_, options.frames_in_background), checkpoint_(dir_),
        history_schedule_{scene_.output.history_interval, progress_.next_history},
        frame_schedule_{scene_.output.frame_interval, progress_.next_frame},
        checkpoint_schedule_{scene_.output.checkpoint_interval, progress_.next_checkpoint},
        progress_line_(solver, options), signals_(options.handle_signals), deadline_(options.deadline),
        heartbeat_(options.heartbeat), on_energy_warning_(options.on_energy_warning),
        heartbeat_seconds_(options.progress_seconds),
        recording_(solver, options.recorder) {}

  RunSummary run();

 private:
  std::optional<std::int64_t> resume_step() const {
    return resuming_ ? std::optional<std::int64_t>(solver_.step_count()) : std::nullopt;
  }
  void start();
  void write_terrain();
  /// One step and the outputs it makes due; returns whether anything was written or must be kept.
  bool step_and_write();
  void write_history_row();
  void write_frame() {
    frames_.write(solver_);
    ++summary_.frames;
  }
  void write_checkpoint() {
    frames_.complete(solver_);  // a resumed run keeps the frames the checkpoint lists: they must be on disk
    progress_.energy_max_released = energy_guard_.max_released();
    progress_.energy_warning = summary_.energy_warning;
    if (progress_.runout_first_row.empty()) progress_.runout_first_row = runout_.first_row();
    checkpoint_.write(solver_, progress_);
    checkpoint_on_disk_ = CheckpointMark{solver_.step_count(), solver_.time()};
  }
  /// The state the folder's checkpoint.h5 holds, if it holds one of this run (its last, or the one
  /// resumed in place): an instability without a last good state points to it, and one with a last
  /// good state keeps it (fail()).
  struct CheckpointMark {
    std::int64_t step;
    double time;
  };
  std::optional<CheckpointMark> checkpoint_on_disk_;
  /// Before the last good state replaces checkpoint.h5: the checkpoint there is kept as
  /// checkpoint_earlier.h5 (what the failure's line then says). A slow blow-up that trips the energy
  /// guard is already under way in a last good state a few steps old: the periodic checkpoint from
  /// before it began is the one to resume with a smaller time.courant, and it was overwritten.
  std::string keep_earlier_checkpoint();
  /// Keeps the current state as the last good one; false when the scene keeps none.
  bool take_snapshot();
  [[noreturn]] void fail(const Error& e);
  /// fail() of a distributed run, on the rank that met the instability (the others may wait in a
  /// collective, so nothing is gathered): runout.json from runout.csv's last row, marked unstable,
  /// and the error's line says what checkpoint.h5 holds.
  [[noreturn]] void fail_distributed(const Error& e);
  void finish();

  Solver& solver_;
  const Scene& scene_;
  Comm comm_;  // a distributed run: rank 0 writes the shared files, every rank its frame piece
  fs::path dir_;
  bool resuming_;
  bool resumed_in_place_;  // resuming in the checkpoint's own folder, which holds the outputs before it
  RunProgress progress_;
  fs::path resume_dir_;
  std::string resume_file_;  // RunOptions::resume_file
  EnergyHistory history_;
  RunoutFiles runout_;
  FrameSeries frames_;
  CheckpointFile checkpoint_;
  OutputSchedule history_schedule_, frame_schedule_, checkpoint_schedule_;
  EnergyGuard energy_guard_;
  FastestParticle fastest_particle() const;  // over every rank (collective)
  void warn_of_energy_growth(const EnergyBudget& e);
  void check_particles_and_dilation();
  bool dilation_warned_ = false;
  Snapshot snapshot_;
  ProgressLine progress_line_;
  SignalCatcher signals_;
  std::optional<std::chrono::steady_clock::time_point> deadline_;
  std::function<void(const Solver&)> heartbeat_;
  std::function<void(const EnergyWarning&)> on_energy_warning_;
  double heartbeat_seconds_;
  std::chrono::steady_clock::time_point last_heartbeat_ = std::chrono::steady_clock::now();
  /// What each rank saw after a step: a signal caught (its number), its deadline passed (1).
  struct StopRequest {
    int signal;
    int late;
  };
  LoopRecording recording_;
  RunSummary summary_;
  double local_updates_ = 0.0;  // this rank's particles summed over the steps taken
};

RunSummary RunLoop::run() {
  start();
  while (!solver_.finished()) {
    bool keep = false;
    recording_.step_begins();
    try {
      keep = step_and_write();
    } catch (const Error& e) {
      // A distributed run cannot go back together to its last good state (the other ranks may be
      // waiting in a collective): the error ends the job (run_command.cpp).
      if (e.kind() != Error::Kind::Instability) throw;
      if (comm_.distributed()) fail_distributed(e);
      fail(e);
    }
    if (comm_.distributed()) frames_.list_finished_frame(solver_);
    // The snapshot never predates a frame or checkpoint, so the failure path writes in order.
    // ParticleStore::copy_from and Solver::state: two parallel loops
    if (keep) recording_.parallel_part(LoopRecording::Part::Snapshot, [&] { return take_snapshot(); }, 2);
    recording_.loop_done();
    StopRequest stop{signals_.caught(), deadline_ && std::chrono::steady_clock::now() >= *deadline_ ? 1 : 0};
    if (comm_.distributed()) {  // every rank stops at the same step when any was signalled or is out of time
      for (const StopRequest& r : comm_.allgather(stop)) stop = {std::max(stop.signal, r.signal), std::max(stop.late, r.late)};
    }
    if ((stop.signal != 0 || stop.late != 0) && !solver_.finished()) {
      write_checkpoint();
      summary_.interrupted_signal = stop.signal;
      summary_.stopped_at_deadline = stop.signal == 0;
      break;
    }
    progress_line_.update();
    if (heartbeat_ && !solver_.finished()) {
      const auto now = std::chrono::steady_clock::now();
      if (std::chrono::duration<double>(now - last_heartbeat_).count() >= heartbeat_seconds_) {
        last_heartbeat_ = now;
        heartbeat_(solver_);
      }
    }
  }
  finish();
  return summary_;
}

void RunLoop::start() {
  summary_.first_step = solver_.step_count();
  summary_.energy_warning = progress_.energy_warning;  // (a resumed run: warned in the part before)
  if (summary_.energy_warning && on_energy_warning_) on_energy_warning_(*summary_.energy_warning);
  // (resumed in place from the folder's checkpoint.h5: it holds this state until the run writes
  // another; resumed from another file, checkpoint_earlier.h5 say, what checkpoint.h5 holds is not known)
  if (resumed_in_place_ && fs::exists(checkpoint_.path()) &&
      (resume_file_.empty() || same_file(resume_file_, checkpoint_.path())))
    checkpoint_on_disk_ = CheckpointMark{solver_.step_count(), solver_.time()};
  if (!resumed_in_place_) record_frame_folder(progress_, dir_, resuming_ ? resume_dir_ : fs::path());
  if (comm_.root()) write_file_atomically((dir_ / "scene.json").string(), scene_file_json(scene_).dump(2) + "\n");
  summary_.pvd_path = frames_.pvd_path();
  summary_.checkpoint_path = checkpoint_.path();
  summary_.runout_path = runout_.history_path();
  if (comm_.root()) write_terrain();
  progress_line_.set_particles(solver_.distribution().particles);
  // The energy guard reads the global ledger, the same on every rank, with the whole run's mass:
  // every rank's and what left through open faces (a restart after outflow changed the guard's
  // floor, and so the energy available that run.json reports). Every rank checks it alike.
  double local_mass = 0.0;
  for (double m : solver_.particles().mass) local_mass += m;
  const double run_mass = comm_.sum_in_rank_order(local_mass) + solver_.outflow_mass();
  if (resuming_) {
    if (comm_.root() && frames_.kept_frames_in_older_order())
      warn("the frames before the checkpoint hold stress and strain in the order of an "
           "earlier build (xx yy zz yz xz xy, unnamed); the frames this run writes use VTK's (xx yy zz xy yz xz, "
           "named): the shear components of the two do not match, so run the scene from the start for a uniform "
           "series");
    // The run's own folder with some or all of the checkpoint's frames deleted, or its energy.csv
    // lost: the restart goes on, but says what its outputs lack. (Into another folder the frames and
    // rows before the checkpoint stay where they are: nothing is missing. The test was "a frame is
    // kept", so a folder that had lost every frame and its history said nothing.)
    if (comm_.root() && resumed_in_place_ && frames_.missing_kept_frames() > 0) {
      std::string folders;
      for (const fs::path& f : frames_.missing_from()) folders += (folders.empty() ? "" : ", ") + f.string();
      warn("{} of the {} frames the checkpoint lists are missing from {}: the series has "
           "gaps there",
           frames_.missing_kept_frames(), progress_.frame_times.size(), folders);
    }
    if (comm_.root() && resumed_in_place_ && history_.kept_rows() == 0)
      warn("{} held no row up to the checkpoint's step {}: the energy history starts at "
           "the restart", (dir_ / "energy.csv").string(), solver_.step_count());
    summary_.initial = progress_.initial;
    energy_guard_ = EnergyGuard(scene_, run_mass, progress_.initial);
    energy_guard_.set_max_released(progress_.energy_max_released);
  } else {
    summary_.initial = solver_.energies();
    progress_.initial = summary_.initial;
    energy_guard_ = EnergyGuard(scene_, run_mass, summary_.initial);
    history_.write(solver_, summary_.initial);
    runout_.write(solver_);
    write_frame();
    // A distributed run lists its first frame now: an instability in the first steps ends the job
    // (MPI_Abort) and would leave a series with nothing to open.
    if (comm_.distributed()) frames_.complete(solver_);
    // Each schedule's first time is one interval after the start.
    progress_.next_frame = scene_.output.frame_interval;
    progress_.next_history = scene_.output.history_interval;
    progress_.next_checkpoint = scene_.output.checkpoint_interval;
  }
  take_snapshot();
}

// The bed the particles slide on, once, over the grid's x and y range (ParaView shows it with the particles).
void RunLoop::write_terrain() {
  const FlumeCoordinates bed = flume_coordinates_of(scene_);
  if (bed.flat()) return;
  const GridGeometry& g = scene_.grid;
  summary_.terrain_path = (dir_ / "terrain.vtu").string();
  write_terrain_vtu(summary_.terrain_path, bed.profile(), g.origin[0], g.origin[0] + g.cells[0] * g.h, g.origin[1],
                    g.origin[1] + g.cells[1] * g.h, 0.25 * g.h, g.h, g.origin[2]);
}

bool RunLoop::step_and_write() {
  local_updates_ += static_cast<double>(solver_.particles().size());
  solver_.step();
  recording_.step_done();
  const double t = solver_.time();
  const bool last = solver_.finished();
  // The history (and the energy guard that reads it): every step when it has no interval.
  if (history_schedule_.interval <= 0.0 || history_schedule_.reached(t) || last) {
    // its parallel regions on many threads: the energies' sum (one), the runout's
    const std::size_t n = solver_.particles().size();
    const int regions = 1 + (runout_.enabled() ? measure_runout_regions(n, kManyThreads) : 0);
    recording_.parallel_part(LoopRecording::Part::History, [&] { write_history_row(); return true; }, regions);
  }
  const bool frame_due = frame_schedule_.reached(t) || last;
  const bool checkpoint_due = checkpoint_schedule_.reached(t) && !last;
  const bool snapshot_due = frame_due || checkpoint_due ||
                            (scene_.guards.snapshot_interval > 0 &&
                             solver_.step_count() - snapshot_.step >= scene_.guards.snapshot_interval);
  // What is written or kept as the last good state is checked in every field first (the solver
  // scans them only every few steps, stability_guards.hpp).
  // (Solver::check_particles: one parallel region; it also looks for unbounded dilation)
  if (snapshot_due)
    recording_.parallel_part(LoopRecording::Part::Snapshot, [&] { check_particles_and_dilation(); return true; }, 1);
  if (frame_due) {
    write_frame();
    frame_schedule_.advance_past(t);
  }
  if (checkpoint_due) {
    checkpoint_schedule_.advance_past(t);
    write_checkpoint();
  }
  return snapshot_due;
}

void RunLoop::write_history_row() {
  ScopedPhase timer(solver_.phase_times(), Phase::Output);
  const EnergyBudget e = solver_.energies();
  history_.write(solver_, e);
  runout_.write(solver_);
  history_schedule_.advance_past(solver_.time());
  const double outflow_gravity = solver_.outflow_gravity();  // (all ranks: a sum over them)
  // Every rank holds the same ledger and so reaches the same verdict; then they find the fastest
  // particle together (rank 0 named its own, another body's, when the fastest was on rank 1), and
  // rank 0 stops the job with it.
  if (energy_guard_.breached(e, outflow_gravity)) {
    const FastestParticle fastest = fastest_particle();
    if (comm_.root()) try {
        energy_guard_.fail(e, fastest, scene_, solver_.step_count(), solver_.time());
      } catch (const Error& breach) {
        throw LedgerInstability(breach.what());  // (the global ledger's, not rank 0's)
      }
    return;
  }
  warn_of_energy_growth(e);
}

FastestParticle RunLoop::fastest_particle() const {
  FastestParticle fastest = FastestParticle::of(solver_.particles());
  if (comm_.distributed())  // (collective)
    for (const FastestParticle& f : comm_.allgather(fastest))
      if (f.before(fastest)) fastest = f;  // (a rank without particles gives id -1, speed2 -1: never before)
  return fastest;
}

// Energy created short of the stop: a run that made 69% of its energy available out of nothing
// ended "completed" without a word (the stop is at 100%, guards.energy_growth_factor). Said once,
// where it first happens, with the particle the stop would name.
void RunLoop::warn_of_energy_growth(const EnergyBudget& e) {
  const double factor = scene_.guards.energy_warning_factor;
  if (summary_.energy_warning || factor <= 0.0) return;
  const double share = energy_guard_.growth_share(e);
  if (!(share > factor)) return;
  summary_.energy_warning = EnergyWarning{solver_.step_count(), solver_.time(), share};
  if (on_energy_warning_) on_energy_warning_(*summary_.energy_warning);
  const FastestParticle fastest = fastest_particle();  // (every rank: the same verdict)
  if (!comm_.root()) return;
  warn("{}: the total energy grew by {:.4g} J, {:.3g}% of the energy available (more than "
       "guards.energy_warning_factor = {}): the scheme is creating energy, the results are suspect; fastest: "
       "{} at ({:.4g}, {:.4g}, {:.4g}) m, {:.4g} m/s. A smaller time.courant usually "
       "helps (docs/reliability.md, \"Instability guards\")",
       step_ended(solver_.step_count(), solver_.time()), e.total() - summary_.initial.total(), 100.0 * share,
       factor, fastest.label(scene_), fastest.x[0], fastest.x[1], fastest.x[2],
       std::sqrt(std::max(fastest.speed2, 0.0)));
}

// Solver::check_particles, and a granular particle dilating without bound, the separation rule being
// off: a hunt's column loosened to V/V0 = 274 and its time step collapsed without a word. Said once,
// where the check first finds one (every rank says its own: the check is per rank, and a collective for
// a warning was not worth it).
void RunLoop::check_particles_and_dilation() {
  if (dilation_warned_) {  // (said once: the volumes need not be compared again)
    solver_.check_particles();
    return;
  }
  const std::string dilation = check_particle_fields_and_dilation(
      solver_.particles(), scene_, solver_.step_count() - 1, solver_.time() - solver_.last_dt());
  if (dilation.empty()) return;
  dilation_warned_ = true;
  warn("{}", dilation);
}

bool RunLoop::take_snapshot() {
  // (a distributed run keeps none: an instability ends its job, see run())
  if (scene_.guards.snapshot_interval <= 0 || comm_.distributed()) return false;
  snapshot_.particles.copy_from(solver_.particles());  // in parallel: a serial copy would be a serial part of the run
  snapshot_.state = solver_.state();
  snapshot_.state.mls_weights.reset();  // a view of the solver's, not kept: a restore from the snapshot fits anew
  snapshot_.progress = progress_;
  snapshot_.progress.energy_max_released = energy_guard_.max_released();
  snapshot_.valid = true;
  snapshot_.step = solver_.step_count();
  return true;
}

// A step failed: go back to the last good state, write it as a frame (unless it is the last frame
// already) and a checkpoint, and stop with the diagnosis.
void RunLoop::fail(const Error& e) {
  std::string message = e.what();
  std::string earlier;  // what became of the checkpoint before (said even if the new one fails)
  try {
    history_.flush();
    if (snapshot_.valid) {
      solver_.restore(snapshot_.particles, snapshot_.state);
      progress_ = snapshot_.progress;
      energy_guard_.set_max_released(snapshot_.progress.energy_max_released);
      std::string frame = "the last frame";
      if (!frames_.has_frame_of_step(solver_.step_count())) {
        frame = frames_.write(solver_);
        ++summary_.frames;
      }
      earlier = keep_earlier_checkpoint();
      write_checkpoint();
      // its runout too, marked unstable (an unstable run wrote no runout.json)
      runout_.finish(solver_, "unstable");
      message += fmt::format(" | last good state ({}) written to {} and checkpoint.h5{}",
                             step_ended(solver_.step_count(), solver_.time()), frame, earlier);
    } else {
      // No snapshot (guards.snapshot_interval = 0): the line said nothing of a state to go back
      // to, though a periodic checkpoint may still lie in the folder, ready to resume from.
      message += fmt::format(" | no last good state kept (guards.snapshot_interval = {})",
                             scene_.guards.snapshot_interval);
      if (checkpoint_on_disk_)
        message += fmt::format("; checkpoint.h5 still holds the last periodic checkpoint ({}): --restart resumes "
                               "from it", step_ended(checkpoint_on_disk_->step, checkpoint_on_disk_->time));
    }
  } catch (const Error& io) {
    message += fmt::format(" | the last good state could not be written: {}{}", io.what(), earlier);
  }
  throw instability_error(message);
}

void RunLoop::fail_distributed(const Error& e) {
  std::string message = e.what();
  try {
    history_.flush();
    runout_.finish_unstable();
  } catch (const Error& io) {
    message += fmt::format(" | runout.json could not be written: {}", io.what());
  }
  // (a distributed run keeps no last good state in memory: take_snapshot)
  if (checkpoint_on_disk_)
    message += fmt::format(" | checkpoint.h5 holds the last periodic checkpoint ({}): --restart resumes from it",
                           step_ended(checkpoint_on_disk_->step, checkpoint_on_disk_->time));
  if (dynamic_cast<const LedgerInstability*>(&e)) throw LedgerInstability(message);
  throw instability_error(message);
}

std::string RunLoop::keep_earlier_checkpoint() {
  if (!checkpoint_on_disk_ || checkpoint_on_disk_->time >= solver_.time()) return "";  // (none, or the last good state's own)
  const fs::path from = checkpoint_.path(), to = from.parent_path() / "checkpoint_earlier.h5";
  std::error_code ec;
  // One kept by an earlier failure in this folder (a run resumed in place since) holds the state
  // from before that blow-up, the earliest there is: never replaced, as a resume from it may fail again.
  if (fs::exists(to, ec)) return fmt::format("; {} (an earlier failure's) left as it was", to.filename().string());
  fs::rename(from, to, ec);
  if (ec) return "";
  return fmt::format("; the checkpoint of t = {:.6g} s kept as {}", checkpoint_on_disk_->time, to.filename().string());
}

void RunLoop::finish() {
  frames_.complete(solver_);  // the last frame on disk and in the .pvd before the run reports it
  history_.flush();
  // (run.json's words: the run ends as `talus run` records it)
  const bool stopped = summary_.interrupted_signal != 0 || summary_.stopped_at_deadline;
  const RunoutFiles::Outcome runout = runout_.finish(solver_, stopped ? "interrupted" : "completed");
  summary_.runout = runout.result;
  summary_.runout_summary_path = runout.summary_path;
  summary_.deposit_path = runout.deposit_path;
  summary_.steps = solver_.step_count();
  summary_.time = solver_.time();
  summary_.particle_updates = comm_.sum_in_rank_order(local_updates_);
  summary_.wall_seconds = progress_line_.elapsed();
  recording_.finish(summary_.wall_seconds, frames_.background_seconds());
  summary_.final = solver_.energies();
  summary_.energy_available = energy_guard_.available();  // (every rank's guard holds the same)
  if (scene_.output.energy_gap_terms) summary_.final_gap = solver_.energy_gap_terms();
  summary_.frames_in_series = frames_.listed();
}

}  // namespace

RunSummary run_scene(Solver& solver, const RunOptions& options) {
  // (in a distributed run rank 0 clears the folder while the others wait)
  if (!options.folder_prepared) prepare_output_folder(options.out_dir, options.resume, solver.comm());
  RunLoop loop(solver, options);
  return loop.run();
}

}  // namespace talus
