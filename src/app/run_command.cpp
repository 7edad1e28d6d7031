// `talus run SCENE`: run a scene and write its outputs.
#include "commands.hpp"
#include "disk_estimate.hpp"
#include "option_checks.hpp"
#include "host_info.hpp"
#include "run_checks.hpp"
#include "run_folder.hpp"
#include "run_record.hpp"
#include "talus/core/simd_dispatch.hpp"
#include "talus/core/error.hpp"
#include "talus/io/atomic_file.hpp"
#include "talus/io/checkpoint.hpp"
#include "talus/driver/folder_lock.hpp"
#include "talus/driver/run_driver.hpp"
#include "talus/driver/run_outputs.hpp"
#include "talus/driver/warning.hpp"
#include "talus/scene/scene_json.hpp"
#include "talus/solver/memory_estimate.hpp"
#include "talus/solver/solver.hpp"
#include "talus/solver/stability_guards.hpp"

#include <fmt/core.h>
#include <fmt/ranges.h>
#include <omp.h>

#include <nlohmann/json.hpp>

#include <unistd.h>

#include <algorithm>
#include <cctype>
#include <chrono>
#include <cmath>
#include <csignal>
#include <cstdio>
#include <ctime>
#include <ostream>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <memory>
#include <optional>

namespace talus::app {

namespace {

/// The exit code of a run that --stop-after stopped with a checkpoint: sysexits.h's EX_TEMPFAIL,
/// "a temporary failure; the user is invited to retry", which a job script can tell from an error.
constexpr int kStoppedAtDeadline = 75;

/// The options of `talus run` (add_run_command says what each means).
struct RunCommandOptions {
  std::string scene_path;
  std::string out_dir;  // empty: runs/<scene name>, or the checkpoint's folder on a restart
  int threads = 0;
  bool quiet = false;
  double progress_every = 0.0;
  std::string restart;
  std::string record_path;
  int record_interval = 37;  // prime: does not alias with sort_interval (20) or output cadences
  double stop_after = 0.0;
  bool foreground_frames = false;
  bool overwrite = false;  // start afresh in a folder that holds an unfinished run
};

// The end-of-run lines of a scene with runout diagnostics (docs/flume.md).
void print_runout(const RunoutResult& r, const RunSummary& summary, const Scene& scene) {
  const RunoutSpec& spec = scene.runout;
  const std::string front =
      r.all_left_time ? fmt::format("every particle had left the grid by t = {:.6g} s; the last front measured (t = {:.6g} s) was",
                                    *r.all_left_time, r.time)
                      : std::string("front");
  fmt::print("talus: runout: {} at s = {:.4f} m, {:.4f} m beyond the gate ({}, s = {:.4f} m)", front, r.front, r.from_gate,
             r.gate_from_scene ? "diagnostics.runout.gate_x" : "the initial front", r.gate_s);
  if (r.beyond_runout_plane) {
    // (negative before the front reaches the plane: said as a distance short of it)
    const double beyond = *r.beyond_runout_plane;
    fmt::print(", {:.4f} m {} the runout plane (starts at s = {:.4f} m)", std::abs(beyond),
               beyond < 0.0 ? "short of" : "onto", *r.runout_plane_s);
  }
  fmt::print("; tail at s = {:.4f} m\n", r.tail);
  // Most of the mass gone through faces other than x+ (the sides, the top, or on a terrain grid an
  // open bed, through which a slide fell whole with nothing said): the front and tail are those of
  // a remnant, not of the flow.
  const double other_faces = r.outflow_mass_share - r.outflow_mass_share_x_plus;
  const bool mostly_elsewhere = other_faces > 0.5;
  // What left through open faces is not in the quantiles: the runout of what stayed in the grid.
  if (r.outflow_mass_share > 0.0 && !r.limited_by_outflow && !mostly_elsewhere)
    fmt::print("talus: runout: front and tail of the mass still in the grid: {:.2f}% left through open faces ({:.2f}% "
               "through x+)\n",
               100.0 * r.outflow_mass_share, 100.0 * r.outflow_mass_share_x_plus);
  if (r.limited_by_outflow)
    warn("runout limited by outflow: {:.2f}% of the mass left through the open face x+, "
         "ahead of the front (more than the {:.2g}% the front quantile leaves ahead of it; {:.2f}% left in all): "
         "the front and tail are quantiles of the mass still in the grid and the flow's front lay beyond the "
         "grid; extend the grid along x",
         100.0 * r.outflow_mass_share_x_plus, 100.0 * (1.0 - spec.front_quantile),
         100.0 * r.outflow_mass_share);
  else if (r.front_at_grid_end)
    warn("runout: the front is within one cell of the grid's end along x: the flow ran to "
         "the end of the grid and may have run farther; extend the grid along x");
  if (mostly_elsewhere) {
    std::string open;
    for (int d = 0; d < 3; ++d)
      for (int side = 0; side < 2; ++side)
        if (!(d == 0 && side == 1) && scene.walls[d][side].type == WallType::Open)
          open += (open.empty() ? "" : ", ") + std::string(face_name(d, side));
    const bool open_bed = scene.grid.has_terrain() && scene.walls[2][0].type == WallType::Open;
    const std::string remnant = r.all_left_time ? std::string("of the last sample with particles in the grid")
                                                : fmt::format("of the {:.2f}% still in the grid", 100.0 * (1.0 - r.outflow_mass_share));
    warn("runout: {:.2f}% of the mass left through open faces other than x+ (open: {}; "
         "{:.2f}% left in all): the front and tail are those {}, not of the flow{}",
         100.0 * other_faces, open, 100.0 * r.outflow_mass_share, remnant,
         open_bed ? "; z- is the bed of this terrain grid, so the material fell through the ground" : "");
  }
  fmt::print("talus: runout history: {}; result: {}{}\n", summary.runout_path, summary.runout_summary_path,
             summary.deposit_path.empty() ? "" : "; deposit thickness: " + summary.deposit_path);
}

// A run on many threads whose colour passes hold fewer blocks than twice the threads: most threads
// wait at each pass's barrier. The scaling model and the 16-core node both found block buffers
// faster there (the default flume: 1.3-1.5x measured at 8 and 16 threads, with OMP_WAIT_POLICY=PASSIVE;
// 1.7x modelled at 16; docs/performance.md "Scaling"); the same test picks out the 1 M bench only
// from 32 threads.
// Nothing changes by itself: the two scatters differ at round-off, and a run's results must not
// depend on its thread count.
std::optional<std::string> scatter_hint(const Scene& scene, const CellSort& sort, int threads) {
  constexpr int kColours = 8;
  if (scene.scatter != ScatterOrder::ColourPasses || scene.grid.has_periodic_axes() || threads < 8) return std::nullopt;
  std::size_t blocks = 0;
  for (int c = 0; c < kColours; ++c) blocks += sort.colour(c).size();
  const double per_pass = static_cast<double>(blocks) / kColours;
  if (per_pass >= 2.0 * threads) return std::nullopt;
  return fmt::format(
      "talus: note: {:.1f} blocks per colour pass on {} threads: most threads wait at each of the {} passes' barriers; "
      "for this scene solver.scatter = \"block_buffers\" scales better (docs/performance.md, \"Scaling\")",
      per_pass, threads, kColours);
}

/// The folder a checkpoint lies in ("." for a bare file name): where a resumed run writes unless
/// --out says otherwise, and where the outputs before the checkpoint are.
std::string checkpoint_folder(const std::string& restart_path) {
  const std::string folder = std::filesystem::path(restart_path).parent_path().string();
  return folder.empty() ? "." : folder;
}

/// A run resumed into another folder than its checkpoint's (--restart with --out) starts that
/// folder's files afresh from the checkpoint's step. Into a folder holding another run's output it
/// kept that run's frames and energy rows below the step and stitched the two runs together.
void require_fresh_folder_for_restart(const std::filesystem::path& dir, const std::string& restart_path) {
  std::error_code ec;
  if (std::filesystem::equivalent(dir, checkpoint_folder(restart_path), ec)) return;  // its own folder: the restart continues the files there
  for (const std::filesystem::path& output : run_output_files(dir))
    if (std::filesystem::exists(output, ec))
      throw input_error(fmt::format("--out {}: it holds another run's {}; resume into the checkpoint's own folder, or "
                                    "into a new or empty one",
                                    dir.string(), output.filename().string()));
}

/// What a run resumed from a checkpoint (--restart) carries on from it.
struct Resumed {
  /// Only the run's progress is kept: the checkpoint's copy of the particles (about 190 B a
  /// particle of the whole scene, on every rank) was held to the run's end.
  RunProgress progress;
  double time = 0.0;                 // the checkpoint's
  std::vector<std::string> changed;  // the keys a restart may change that this scene changes
};

/// Reads the checkpoint `restart` (every rank) and restores it into `solver`, checked against the
/// scene before anything is written; rank 0 names the keys the scene changes.
Resumed restore_for_run(Solver& solver, const std::string& restart, const Comm& world) {
  Checkpoint checkpoint;
  world.agree([&] {  // (a rank may not see the file)
    require_checkpoint_file(restart);
    checkpoint = read_checkpoint(restart, world);
  });
  restore_checkpoint(solver, checkpoint, restart);
  std::vector<std::string> changed = restart_changes(checkpoint, solver.scene());  // (said once accepted: the banner)
  return Resumed{checkpoint.run, checkpoint.solver.time, std::move(changed)};
}

/// What the run would write where it must not, refused before anything is written.
void check_output_folder(const std::string& dir, const RunCommandOptions& o, const Scene& scene, bool resumed) {
  require_outputs_spare_inputs(dir, o.scene_path, scene, o.restart, o.record_path);
  if (resumed && !o.out_dir.empty()) require_fresh_folder_for_restart(dir, o.restart);
  // Every rank sees the same folder and stops alike (rank 0 reports); --record-work is refused under mpirun.
  check_writable_folder(dir, "output folder");
  require_no_folder_in_place_of_an_output(dir);
  if (!o.record_path.empty()) check_writable_file(o.record_path, "--record-work", dir);
}

/// One run at a time in a folder: claimed into `lock` before anything in it is cleared (rank 0
/// claims it for the job and tells the others; driver/folder_lock.hpp).
void claim_output_folder(const std::string& dir, const Comm& world, std::optional<FolderLock>& lock) {
  std::string refusal;
  if (world.root()) try {
      lock.emplace(dir);
    } catch (const Error& e) {
      if (!world.distributed()) throw;
      refusal = e.what();
    }
  if (world.distributed() && !(refusal = world.broadcast(refusal)).empty()) throw input_error(refusal);
}

/// Rank 0's lines before the first step: the restart, the run's size and where it writes, and
/// the notes and warnings on it.
void print_start_banner(const Solver& solver, std::int64_t particles, const MemoryEstimate& memory,
                        const MachineShare& share, const std::string& dir, const std::string& restart,
                        const Resumed* resumed, const Comm& world) {
  if (resumed && world.root()) {
    if (const auto line = restart_changes_line(resumed->changed)) fmt::print("{}\n", *line);
    fmt::print("talus: restart from {} at step {}, t = {:.6g} s\n", restart, solver.step_count(), solver.time());
    if (same_file(dir, checkpoint_folder(restart)))
      if (const auto w = rewind_warning(dir, resumed->time, resumed->progress.frame_times.size())) warn("{}", *w);
  }
  const int threads = omp_get_max_threads();
  if (world.root())
    fmt::print("talus: {} particles, {}{} thread{}, {} kernels, about {} of memory{}, output in {}\n", particles,
               world.distributed() ? fmt::format("{} ranks x ", world.size()) : "", threads, threads == 1 ? "" : "s",
               active_isa(), format_bytes(double(memory.total())),
               world.distributed() ? fmt::format(" (all ranks; {} on this machine, where rank 0 gathers every particle)",
                                                 format_bytes(double(bytes_on_this_machine(solver.scene(), memory, share))))
                                   : "",
               dir);
  if (world.root() && !world.distributed())
    if (const auto hint = scatter_hint(solver.scene(), solver.cell_sort(), threads)) fmt::print("{}\n", *hint);
  if (world.root())  // (the same line as `talus check`'s, app/disk_estimate.hpp)
    if (const auto w = disk_warning(estimate_disk(solver.scene(), std::size_t(particles), dir), dir)) warn("{}", *w);
  // Out now, ahead of the progress lines and any error on stderr: a log of both (`> log 2>&1`)
  // had this banner after the error that ended the run.
  std::fflush(stdout);
}

/// How the driver runs it: the command's options, and a resumed run's progress (`resume`).
RunOptions run_options(const RunCommandOptions& o, const std::string& dir, std::chrono::steady_clock::time_point started,
                       const RunProgress* resume) {
  RunOptions options;
  options.out_dir = dir;
  options.progress = !o.quiet;
  options.progress_seconds = o.progress_every > 0.0 ? o.progress_every : isatty(fileno(stderr)) ? 2.0 : 30.0;
  options.frames_in_background = !o.foreground_frames;
  options.folder_prepared = true;
  if (o.stop_after > 0.0)
    options.deadline = started + std::chrono::duration_cast<std::chrono::steady_clock::duration>(
                                     std::chrono::duration<double>(o.stop_after));
  if (resume) {
    options.resume = resume;
    options.resume_dir = checkpoint_folder(o.restart);
    options.resume_file = o.restart;
  }
  return options;
}

/// run_scene, with the end of an error written to the record. One rank: the error goes on to
/// main(), which prints it. Under mpirun this rank may have failed alone while the others wait in
/// a collective: it names itself and ends the whole job with its exit code (MPI_Abort), so nothing
/// hangs. The line goes out before the record is written: two ranks that failed in one step both
/// wrote run.json first, and the first abort cut the other's line, so the log named one rank and
/// the record another. An error the ranks agreed on (Comm::agree: a frame's piece or the checkpoint
/// that could not be written) is rank 0's to record and to say, once; no rank aborts.
RunSummary run_or_abort_rank(Solver& solver, const RunOptions& options, RunRecord& record, const Comm& world) {
  try {
    return run_scene(solver, options);
  } catch (const std::exception& e) {
    // (a talus::Error is said as an error, with its exit code; anything else is an internal error, 4, as main() says it)
    const Error* error = dynamic_cast<const Error*>(&e);
    // (every rank threw it together, rank 0's naming the rank: main() prints it on rank 0 and every
    // rank exits with its code, no rank being left in a collective)
    const bool agreed = error && error->agreed();
    if (world.distributed() && !agreed) {
      // (the energy guard's breach is of the global ledger: no rank's own)
      if (dynamic_cast<const LedgerInstability*>(&e))
        fmt::print(stderr, "talus: error (energy guard, all ranks): {}\n", e.what());
      else
        fmt::print(stderr, "talus: {} on rank {} of {}: {}\n", error ? "error" : "internal error", world.rank(),
                   world.size(), e.what());
      std::fflush(stderr);
    }
    if (error)
      record.end_with_error(solver, *error);
    else
      record.end_with_error(solver, e);
    if (!world.distributed() || agreed) throw;
    world.abort(error ? error->exit_code() : 4);
  }
}

/// --record-work: the record of the whole run, as JSON (tools/scaling_model.py).
void write_work_record(const WorkRecorder& recorder, const Solver& solver, const RunSummary& summary,
                       const std::string& path) {
  nlohmann::json meta = WorkRecorder::threading_meta();
  meta["source"] = "talus run";
  meta["scene"] = solver.scene().name;
  meta["threads"] = omp_get_max_threads();
  meta["block_cells"] = solver.cell_sort().block_cells();
  meta["run_wall_seconds"] = summary.wall_seconds;
  meta["run_particles_end"] = solver.particles().size();
  write_file_atomically(path, [&](std::ostream& out) { recorder.write_json(out, meta); });
  fmt::print("talus: work record: {} steps, {}\n", recorder.steps().size(), path);
}

/// The name of a signal that stops a run (driver/run_driver.cpp SignalCatcher: "stopped by signal
/// 10" left the user to look 10 up).
std::string signal_name(int signal) {
  switch (signal) {
    case SIGINT: return "SIGINT";
    case SIGTERM: return "SIGTERM";
    case SIGUSR1: return "SIGUSR1";
    default: return strsignal(signal);
  }
}

/// The lines of a run that a signal or --stop-after stopped: where, and how to resume it.
void print_stop(const RunSummary& summary, std::chrono::steady_clock::time_point started, const std::string& scene_path,
                int threads_option, const Comm& world) {
  if (summary.stopped_at_deadline)
    fmt::print("talus: stopped after {:.1f} s of wall clock (--stop-after) at step {}, t = {:.6g} s; checkpoint {}\n",
               std::chrono::duration<double>(std::chrono::steady_clock::now() - started).count(), summary.steps,
               summary.time, summary.checkpoint_path);
  else
    fmt::print("talus: stopped by signal {} ({}) at step {}, t = {:.6g} s; checkpoint {}\n", summary.interrupted_signal,
               signal_name(summary.interrupted_signal), summary.steps, summary.time, summary.checkpoint_path);
  // (any rank count resumes it; the same one continues bit for bit)
  // (with the --threads it was started with: under mpirun the default is another count)
  fmt::print("talus: resume with: {}{} run {} --restart {}{}\n",
             world.distributed() ? fmt::format("mpirun -np {} ", world.size()) : "", program_word(), shell_word(scene_path),
             shell_word(summary.checkpoint_path), threads_option > 0 ? fmt::format(" --threads {}", threads_option) : "");
}

/// MLS smoothing's line at the end of a run: what the guard left unsmoothed and how much the fits
/// changed, or a warning when they did (almost) nothing; and the reuse of the weights.
void print_smoothing_report(const Solver& solver) {
  // the share of the particle-passes the guard judged: those of the smoothed bodies
  const double unsmoothed_share =
      solver.guarded_total() > 0 ? double(solver.unsmoothed_total()) / double(solver.guarded_total()) : 0.0;
  const MlsSettings& mls = solver.scene().smoothing.mls;
  if (unsmoothed_share > 0.5) {
    // A body of a few particles, or one or two particles thick, gives A too few neighbours (or too
    // few layers of them) for the basis at any radius: the guard skipped (nearly) every particle,
    // and the info line's "100%" was easy to read past as if the scene were smoothed.
    warn("MLS smoothing had {} effect: the guard left {} of the {} particle-passes "
         "unsmoothed ({:.3g}%, {} passes): too few neighbours within radius_factor {} cells, or too few "
         "layers of them, for the {} basis (a body of a few particles, or one or two particles thick: leave "
         "that axis out with solver.smoothing.axes; docs/verification.md, \"MLS strain smoothing\", the "
         "guard)",
         unsmoothed_share == 1.0 ? "no" : "almost no", solver.unsmoothed_total(), solver.guarded_total(),
         100.0 * unsmoothed_share, solver.smoothing_passes(), mls.radius_factor, to_string(mls.basis));
  } else {
    fmt::print("talus: MLS smoothing: {} passes; the guard left {} particle-passes unsmoothed ({:.3g}%); the fit "
               "changed the strain increments by {:.2f} on average, at most {:.2f} (RMS of the change / RMS of the "
               "increments; near 1 means hourglass modes, docs/verification.md \"MLS radius\")\n",
               solver.smoothing_passes(), solver.unsmoothed_total(), 100.0 * unsmoothed_share,
               solver.mean_smoothing_change(), solver.max_smoothing_change());
  }
  if (solver.scene().smoothing.mls.variant == MlsVariant::Reused)
    fmt::print("talus: MLS weights reused: {} of the {} passes fitted (reuse_strain {}), the others reused the "
               "weights of the last fit ({:.0f} B/particle)\n",
               solver.smoothing_fits(), solver.smoothing_passes(), solver.scene().smoothing.mls.reuse_strain,
               double(solver.mls_weight_bytes()) / std::max<double>(1.0, double(solver.particles().size())));
}

/// What every rank counts at the end of a run (collectives), for rank 0's report.
struct RunTotals {
  DistributionStats end;  // the slabs at the end
  std::int64_t outflow_particles = 0;
  double outflow_mass = 0.0;
  double mass = 0.0;  // every rank's and what left through open faces
};

/// The lines of a run that reached its end: steps and rate, the energy budget, the smoothing, the
/// outflow, and the files to open.
void print_run_report(const Solver& solver, const RunSummary& summary, const RunTotals& totals, const std::string& dir,
                      const std::string& restart, const std::optional<Resumed>& resumed, const Comm& world) {
  const DistributionStats& end = totals.end;
  const double scale = summary.energy_scale();
  // (a resumed run's rate counts the steps it took, not those before its checkpoint)
  const std::int64_t taken = summary.steps - summary.first_step;
  // (below 0.1 M/s with three significant digits, without an exponent: a small run printed "0.00")
  const double rate = summary.particle_updates / summary.wall_seconds / 1e6;
  const int digits = rate > 0.0 && rate < 0.1 ? std::min(9, 1 - int(std::floor(std::log10(rate))) + 1) : 2;
  fmt::print("talus: done: {} steps to t = {:.6g} s{} in {:.2f} s ({:.{}f} M particle-updates/s)\n", summary.steps,
             summary.time, taken == summary.steps ? "" : fmt::format(" ({} in this run)", taken), summary.wall_seconds,
             rate, digits);
  if (solver.stopped_at_max_steps())
    fmt::print("talus: stopped at time.max_steps = {}, before its end time {:.6g} s\n", solver.scene().max_steps,
               solver.scene().end_time);
  if (solver.emptied())
    fmt::print("talus: every particle had left through the open faces at t = {:.6g} s: the run ended there, before "
               "its end time {:.6g} s\n", summary.time, solver.scene().end_time);
  if (world.distributed())
    fmt::print("talus: {} ranks: slabs out of balance by at most {:.2f} (largest rank's particles / mean), {} rebalances, "
               "{} particles migrated, {:.3g} MB of node sums exchanged ({:.3g} kB a step)\n",
               end.ranks, end.max_imbalance, end.rebalances, end.migrated, end.exchange_bytes / 1e6,
               taken > 0 ? end.exchange_bytes / 1e3 / taken : 0.0);
  fmt::print("talus: energy budget closes to {:.3e} of the energy available ({:.4g} J of {:.4g} J: the initial kinetic "
             "and strain energy and the potential energy released)\n",
             summary.energy_budget_gap(), summary.energy_budget_gap_joules(), summary.energy_scale());
  if (summary.energy_warning)  // (said as it happened, far up a long log: said again where the run is judged)
    fmt::print(stderr, "talus: warning: the total energy grew by more than guards.energy_warning_factor = {} of the "
               "energy available ({:.3g}% {}; {:+.3g}% at the end): the scheme created energy, the results are "
               "suspect; a smaller time.courant usually helps\n",
               solver.scene().guards.energy_warning_factor, 100.0 * summary.energy_warning->share,
               step_ended(summary.energy_warning->step, summary.energy_warning->time),
               100.0 * summary.energy_budget_gap());
  if (solver.scene().output.energy_gap_terms) {
    // the parts of that gap (docs/theory.md, "Where the budget's gap comes from"), on the same scale
    const EnergyGapParts p = energy_gap_parts(summary.initial, summary.final, summary.final_gap);
    fmt::print("talus: made of: stress work booked beyond the grid's {:+.3e}, walls {:+.3e}, gravity {:+.3e}, "
               "transfer loss {:+.3e} (docs/theory.md, \"Where the budget's gap comes from\")\n",
               p.stress / scale, p.walls / scale, p.gravity / scale, p.transfer / scale);
  }
  if (solver.smoother() && solver.smoothing_passes() > 0) print_smoothing_report(solver);
  if (totals.outflow_particles > 0)
    fmt::print("talus: {} particles ({:.4g} kg, {:.2f}% of the mass) left through open faces (removed; energy column "
               "'outflow')\n",
               totals.outflow_particles, totals.outflow_mass, 100.0 * totals.outflow_mass / totals.mass);
  // (a resumed run's series holds the frames before the checkpoint too)
  const std::string written = summary.frames_in_series == summary.frames
                                  ? ""
                                  : fmt::format(", {} written by this run", summary.frames);
  fmt::print("talus: ParaView series: {} ({} frame{}{}); energy history: {}/energy.csv; run record: {}/run.json\n",
             summary.pvd_path, summary.frames_in_series, summary.frames_in_series == 1 ? "" : "s", written, dir, dir);
  // (resumed into another folder: its series, energy.csv and runout.csv start at the checkpoint,
  // which a user opening that folder alone could not tell, docs/reliability.md)
  if (resumed && !same_file(dir, checkpoint_folder(restart)))
    fmt::print("talus: {}'s series and histories start at the checkpoint, t = {:.6g} s; the part before it is in {}\n",
               dir, resumed->time, checkpoint_folder(restart));
  if (const auto note = older_checkpoint_note(dir, summary.time)) fmt::print("{}\n", *note);
  if (!summary.terrain_path.empty()) fmt::print("talus: terrain surface: {} (open it with the series)\n", summary.terrain_path);
  if (summary.runout) print_runout(*summary.runout, summary, solver.scene());
}

void run_command(const RunCommandOptions& o, const std::string& isa) {
  const auto started = std::chrono::steady_clock::now();  // --stop-after and run.json count from here
  const std::time_t utc_started = std::time(nullptr);
  // Under mpirun: every rank reads the scene and builds its slab of the solver; rank 0 speaks.
  const Comm world = Comm::world();
  const int threads = set_rank_threads(o.threads, world);  // (collective)
  const std::optional<std::string> oversubscribed = oversubscription_warning(world, o.threads, threads);  // (collective)
  select_isa_option(isa);
  if (world.distributed() && !o.record_path.empty())
    throw input_error("--record-work: the work recorder times one rank's threads; run it without mpirun");
  Scene scene = read_scene_file(o.scene_path);  // validated before anything is written
  if (world.root()) print_warnings(scene, oversubscribed ? std::vector<std::string>{*oversubscribed} : std::vector<std::string>{});
  const MemoryEstimate memory = estimate_memory(scene);
  // a scene that cannot fit stops here, before anything is allocated (each rank checks its own
  // machine; one that refuses stops every rank)
  const MachineShare share = machine_share(world, o.restart);
  world.agree([&] { require_memory_fits(scene, memory, share); });
  if (world.root())
    if (const auto w = memory_bound_warning(memory, share)) warn("{}", *w);
  std::string dir = o.out_dir.empty() ? "runs/" + scene.name : o.out_dir;
  Solver solver(std::move(scene), world);
  std::optional<Resumed> resumed;
  if (!o.restart.empty()) {  // checked against the scene before anything is written
    resumed = restore_for_run(solver, o.restart, world);
    if (o.out_dir.empty()) dir = checkpoint_folder(o.restart);
  }
  check_output_folder(dir, o, solver.scene(), resumed.has_value());
  std::optional<FolderLock> lock;
  claim_output_folder(dir, world, lock);
  if (!resumed) world.agree([&] { require_no_unfinished_run(dir, o.overwrite); });
  // Made (or cleared) here, before the run starts: a folder that cannot be used is an error every
  // rank meets alike (rank 0 prepares it and tells the others), said once, with nothing started.
  const RunProgress* resume = resumed ? &resumed->progress : nullptr;
  prepare_output_folder(dir, resume, world);
  const DistributionStats start = solver.distribution();
  print_start_banner(solver, start.particles, memory, share, dir, o.restart, resumed ? &*resumed : nullptr,
                     world);
  RunOptions options = run_options(o, dir, started, resume);
  std::unique_ptr<WorkRecorder> recorder;
  if (!o.record_path.empty()) {
    recorder = std::make_unique<WorkRecorder>(1000, o.record_interval, RecordSpan::WholeRun);
    options.recorder = recorder.get();
  }
  RunRecord record(dir, solver,
                   RunStart{o.scene_path, o.restart, resumed ? resumed->changed : std::vector<std::string>{},
                            memory.total(), start.particles, started, utc_started},
                   world);
  options.heartbeat = [&record](const Solver& s) { record.progress(s); };
  options.on_energy_warning = [&record](const EnergyWarning& w) { record.energy_warning(w); };
  const RunSummary summary = run_or_abort_rank(solver, options, record, world);
  RunTotals totals;
  totals.end = solver.distribution();
  totals.outflow_particles = solver.outflow_particles();
  record.end(solver, summary, RunEnd{totals.end.particles, totals.outflow_particles, solver.outflow_faces()});
  totals.outflow_mass = solver.outflow_mass();
  double mass = totals.outflow_mass;
  for (double m : solver.particles().mass) mass += m;
  totals.mass = world.distributed() ? world.sum_in_rank_order(mass - totals.outflow_mass) + totals.outflow_mass : mass;
  if (summary.interrupted_signal) exit_code() = 128 + summary.interrupted_signal;
  if (summary.stopped_at_deadline) exit_code() = kStoppedAtDeadline;
  if (!world.root()) return;
  if (recorder) write_work_record(*recorder, solver, summary, o.record_path);
  if (summary.interrupted_signal || summary.stopped_at_deadline)
    print_stop(summary, started, o.scene_path, o.threads, world);
  else
    print_run_report(solver, summary, totals, dir, o.restart, resumed, world);
}

}  // namespace

void add_run_command(CLI::App& app) {
  auto* cmd = app.add_subcommand("run", "Run a scene: write a ParaView series (.pvd + .vtu frames) and an energy history");
  auto o = std::make_shared<RunCommandOptions>();
  auto isa = std::make_shared<std::string>();
  cmd->add_option("scene", o->scene_path, "Scene file (JSON); see docs/scene-reference.md")->required();
  add_isa_option(cmd, isa);
  refuse_empty(cmd->add_option("--out", o->out_dir, "Output folder (default: runs/<scene name>)"),
               "give a folder, or leave --out out for runs/<scene name>");
  check_range(cmd->add_option("--threads", o->threads, "OpenMP threads (default: OMP_NUM_THREADS, else the CPUs this process may use; under mpirun "
                                                             "shared among the ranks on the host that may use them)"), 1, 4096);
  cmd->add_flag("--quiet", o->quiet, "No progress line");
  check_range(cmd->add_option("--progress-every", o->progress_every,
                              "Seconds between progress lines (default: 2 on a terminal, where the line is rewritten "
                              "in place; 30 into a file or pipe, where each is a new line of the log)"),
              0.1, 86400.0);
  CLI::Option* restart_option = refuse_empty(
      cmd->add_option("--restart", o->restart,
                      "Continue from a checkpoint (e.g. runs/<name>/checkpoint.h5) of this scene (only time.end, "
                      "time.courant, time.max_steps, guards, output.checkpoint_interval, description and comment may "
                      "differ); output goes to the checkpoint's folder unless --out is given"),
      "give a checkpoint file, or leave --restart out for a fresh run");
  cmd->add_flag("--overwrite", o->overwrite,
                "Start afresh in an output folder that holds an unfinished run (interrupted, unstable, failed or "
                "killed) with its checkpoint.h5, deleting them (without it such a run is refused, naming the resume "
                "command)")
      ->excludes(restart_option);
  CLI::Option* record_work = refuse_empty(cmd->add_option("--record-work", o->record_path,
                               "Record the work of every block and parallel region of every --record-interval-th step, "
                               "as JSON (tools/scaling_model.py, docs/performance.md \"Scaling\"); a record keeps at "
                               "most 1000 steps and 4 M block entries (about 200 MB): past that it keeps every third "
                               "step and triples the interval, so that it spans the whole run"),
               "give a file, or leave --record-work out");
  // (given alone it was ignored without a word)
  check_range(cmd->add_option("--record-interval", o->record_interval, "Steps between the steps --record-work records"), 1,
              1000000)
      ->capture_default_str()
      ->needs(record_work);
  check_duration(cmd->add_option(
      "--stop-after", o->stop_after,
      "Stop once the run has taken this long (wall clock from its start: 3h50m, 90m, 5400s, ...), at the end of "
      "a step, with a checkpoint to resume from, and exit with code 75: for a batch job's time limit, less a "
      "margin for the checkpoint"));
  cmd->footer(run_help_footer());
  cmd->add_flag("--foreground-frames", o->foreground_frames,
                "Write each frame before the next step starts (by default a frame's compression and file write "
                "run on a thread of their own while the next steps run)");
  cmd->callback([o, isa]() { run_command(*o, *isa); });
}

}  // namespace talus::app
