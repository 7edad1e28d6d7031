#include "talus/io/run_driver.hpp"

#include "talus/core/error.hpp"
#include "talus/io/runout_output.hpp"
#include "talus/io/vtu_writer.hpp"
#include "talus/scene/scene_json.hpp"
#include "talus/solver/stability_guards.hpp"

#include <fmt/core.h>
#include <unistd.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <csignal>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <sstream>

namespace talus {

namespace fs = std::filesystem;

namespace {

/// The columns of energy.csv (one per EnergyBudget term, then the total).
constexpr const char* kEnergyHeader =
    "time,step,dt,kinetic,strain,gravity,friction_work,plastic_work,outflow,damping,total";


volatile std::sig_atomic_t g_signal = 0;

extern "C" void on_stop_signal(int sig) { g_signal = sig; }

/// SIGINT/SIGTERM set a flag for the run loop while this lives; a second signal acts as usual
/// (SA_RESETHAND), so a run that does not stop can still be killed.
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
  }
  ~SignalCatcher() {
    if (!enabled_) return;
    sigaction(SIGINT, &old_int_, nullptr);
    sigaction(SIGTERM, &old_term_, nullptr);
  }
  int caught() const { return enabled_ ? static_cast<int>(g_signal) : 0; }

 private:
  bool enabled_;
  struct sigaction old_int_ {}, old_term_ {};
};

std::string frame_name(std::size_t index) { return fmt::format("frames/particles_{:06}.vtu", index); }

void remove_temporaries(const fs::path& dir) {
  std::error_code ec;
  for (const fs::path& d : {dir, dir / "frames"})
    for (const auto& entry : fs::directory_iterator(d, ec))
      if (entry.path().extension() == ".tmp") fs::remove(entry.path(), ec);
}

void prepare_output_folder(const std::string& dir) {
  std::error_code ec;
  fs::create_directories(fs::path(dir) / "frames", ec);
  if (ec) throw io_error(fmt::format("cannot create output folder {}: {}", dir, ec.message()));
  // Replace the outputs of an earlier run in the same folder, so no stale frame survives.
  for (const auto& entry : fs::directory_iterator(fs::path(dir) / "frames"))
    if (entry.path().extension() == ".vtu") fs::remove(entry.path());
  for (const char* f : {"particles.pvd", "energy.csv", "scene.json", "checkpoint.h5", "runout.csv", "runout.json", "deposit.csv", "terrain.vtu"})
    fs::remove(fs::path(dir) / f, ec);
  remove_temporaries(dir);
}

/// A restart: keep the frames the checkpoint lists, drop later ones, and cut the energy history
/// back to the checkpoint's step (rewritten atomically).
void prepare_output_folder_for_resume(const std::string& dir, const RunProgress& run, std::int64_t step) {
  std::error_code ec;
  fs::create_directories(fs::path(dir) / "frames", ec);
  if (ec) throw io_error(fmt::format("cannot create output folder {}: {}", dir, ec.message()));
  remove_temporaries(dir);
  for (const auto& entry : fs::directory_iterator(fs::path(dir) / "frames")) {
    const std::string name = entry.path().filename().string();
    unsigned long index = 0;
    if (entry.path().extension() == ".vtu" && std::sscanf(name.c_str(), "particles_%lu.vtu", &index) == 1 &&
        index >= run.frame_times.size())
      fs::remove(entry.path(), ec);
  }
  const fs::path history = fs::path(dir) / "energy.csv";
  std::string kept = std::string(kEnergyHeader) + "\n";
  const auto commas = std::count(kEnergyHeader, kEnergyHeader + std::strlen(kEnergyHeader), ',');
  std::ifstream in(history);
  std::string line;
  bool header = true;
  while (std::getline(in, line)) {
    if (header) {
      header = false;
      continue;
    }
    // time,step,...: keep complete rows up to the checkpoint's step.
    const auto c1 = line.find(',');
    const auto c2 = c1 == std::string::npos ? std::string::npos : line.find(',', c1 + 1);
    if (c2 == std::string::npos || std::count(line.begin(), line.end(), ',') != commas) break;
    long long row_step = 0;
    try {
      row_step = std::stoll(line.substr(c1 + 1, c2 - c1 - 1));
    } catch (const std::exception&) {
      break;
    }
    if (row_step > step) break;
    kept += line + "\n";
  }
  in.close();
  write_file_atomically(history.string(), kept);
}

/// A restart with runout diagnostics: keep the rows of runout.csv up to the checkpoint's step
/// (rewritten atomically) and return the first and the last of them; empty if there are none.
std::optional<std::pair<RunoutSample, RunoutSample>> cut_runout_history(const fs::path& path, std::int64_t step) {
  std::string kept = runout_csv_header() + "\n";
  std::optional<RunoutSample> first, last;
  std::ifstream in(path);
  std::string line;
  std::getline(in, line);  // header
  while (std::getline(in, line)) {
    const auto row = parse_runout_csv_row(line);
    if (!row || row->step > step) break;
    if (!first) first = row;
    last = row;
    kept += line + "\n";
  }
  in.close();
  write_file_atomically(path.string(), kept);
  if (!first) return std::nullopt;
  return std::make_pair(*first, *last);
}

std::string format_duration(double seconds) {
  if (!std::isfinite(seconds) || seconds < 0) return "?";
  const long s = std::lround(seconds);
  if (s >= 3600) return fmt::format("{}h{:02}m", s / 3600, (s / 60) % 60);
  if (s >= 60) return fmt::format("{}m{:02}s", s / 60, s % 60);
  return fmt::format("{}s", s);
}

/// The last state that passed every guard, kept in memory to be written when a later step fails.
struct Snapshot {
  bool valid = false;
  ParticleStore particles;
  SolverState state;
  RunProgress progress;
};

}  // namespace

RunSummary run_scene(Solver& solver, const RunOptions& options) {
  const Scene& scene = solver.scene();
  const fs::path dir(options.out_dir);
  const bool resuming = options.resume != nullptr;
  if (resuming)
    prepare_output_folder_for_resume(options.out_dir, *options.resume, solver.step_count());
  else
    prepare_output_folder(options.out_dir);
  write_file_atomically((dir / "scene.json").string(), scene_to_json(scene).dump(2) + "\n");

  RunSummary summary;
  summary.pvd_path = (dir / "particles.pvd").string();
  summary.checkpoint_path = (dir / "checkpoint.h5").string();
  PvdIndex pvd(summary.pvd_path);
  RunProgress progress;
  if (resuming) {
    progress = *options.resume;
    std::vector<std::pair<double, std::string>> entries;
    for (std::size_t i = 0; i < progress.frame_times.size(); ++i) entries.emplace_back(progress.frame_times[i], frame_name(i));
    pvd.assign(std::move(entries));
  }
  std::ofstream history(dir / "energy.csv", resuming ? std::ios::app : std::ios::trunc);
  if (!history) throw io_error(fmt::format("cannot write {}", (dir / "energy.csv").string()));
  if (!resuming) history << kEnergyHeader << "\n";

  // Runout diagnostics (docs/flume.md): only when the scene asks for them.
  std::optional<RunoutMonitor> runout;
  std::ofstream runout_history;
  if (scene.runout.enabled) {
    runout.emplace(scene.runout, flume_coordinates_of(scene));
    summary.runout_path = (dir / "runout.csv").string();
    if (resuming) {
      if (const auto kept = cut_runout_history(summary.runout_path, solver.step_count()))
        runout->resume(kept->first, kept->second);
    }
    runout_history.open(summary.runout_path, resuming ? std::ios::app : std::ios::trunc);
    if (!runout_history) throw io_error(fmt::format("cannot write {}", summary.runout_path));
    if (!resuming) runout_history << runout_csv_header() << "\n";
  }
  if (const FlumeCoordinates bed = flume_coordinates_of(scene); !bed.flat()) {
    // The terrain surface, once, over the grid's x and y range (ParaView shows it with the particles).
    const GridGeometry& g = scene.grid;
    summary.terrain_path = (dir / "terrain.vtu").string();
    write_terrain_vtu(summary.terrain_path, bed.profile(), g.origin[0], g.origin[0] + g.cells[0] * g.h, g.origin[1],
                      g.origin[1] + g.cells[1] * g.h, 0.25 * g.h);
  }
  auto write_runout = [&]() {
    if (!runout) return;
    runout_history << runout_csv_row(runout->sample(solver.particles(), solver.time(), solver.step_count())) << "\n";
    runout_history.flush();
  };

  // Each row is flushed on its own, so a killed run leaves only whole rows behind.
  auto write_history = [&](const EnergyBudget& e) {
    history << fmt::format("{:.10e},{},{:.6e},{:.10e},{:.10e},{:.10e},{:.10e},{:.10e},{:.10e},{:.10e},{:.10e}\n",
                           solver.time(), solver.step_count(), solver.last_dt(), e.kinetic, e.strain, e.gravity,
                           e.friction_work, e.plastic_work, e.outflow, e.damping, e.total());
    history.flush();
  };
  auto write_frame = [&]() {
    ScopedPhase timer(solver.phase_times(), Phase::Output);
    const std::string name = frame_name(progress.frame_times.size());
    write_particles_vtu((dir / name).string(), solver.particles(), scene.output.compress);
    pvd.add(solver.time(), name);
    progress.frame_times.push_back(solver.time());
    progress.frame_steps.push_back(solver.step_count());
    ++summary.frames;
  };
  EnergyGuard energy_guard;
  auto write_checkpoint_now = [&]() {
    ScopedPhase timer(solver.phase_times(), Phase::Output);
    progress.energy_max_released = energy_guard.max_released();
    write_checkpoint(summary.checkpoint_path, solver, progress);
    ++summary.checkpoints;
  };

  if (resuming) {
    summary.initial = progress.initial;
    energy_guard = EnergyGuard(scene, solver.particles(), progress.initial);
    energy_guard.set_max_released(progress.energy_max_released);
  } else {
    summary.initial = solver.energies();
    progress.initial = summary.initial;
    energy_guard = EnergyGuard(scene, solver.particles(), summary.initial);
    write_history(summary.initial);
    write_runout();
    write_frame();
    progress.next_frame = scene.output.frame_interval;
    progress.next_history = scene.output.history_interval;
    progress.next_checkpoint = scene.output.checkpoint_interval;
  }

  Snapshot snapshot;
  const int snapshot_interval = scene.guards.snapshot_interval;
  std::int64_t last_snapshot_step = -1;
  auto take_snapshot = [&]() {
    if (snapshot_interval <= 0) return;
    snapshot.particles = solver.particles();
    snapshot.state = solver.state();
    snapshot.progress = progress;
    snapshot.progress.energy_max_released = energy_guard.max_released();
    snapshot.valid = true;
    last_snapshot_step = solver.step_count();
  };
  take_snapshot();

  // A step failed: go back to the last good state, write it as a frame (unless it is the last
  // frame already) and a checkpoint, and stop with the diagnosis.
  auto fail = [&](const Error& e) {
    std::string message = e.what();
    try {
      history.flush();
      if (snapshot.valid) {
        solver.restore(snapshot.particles, snapshot.state);
        progress = snapshot.progress;
        energy_guard.set_max_released(snapshot.progress.energy_max_released);
        std::string frame = "the last frame";
        if (progress.frame_steps.empty() || progress.frame_steps.back() != solver.step_count()) {
          write_frame();
          frame = frame_name(progress.frame_times.size() - 1);
        }
        write_checkpoint_now();
        message += fmt::format(" | last good state (after step {}, t = {:.6g} s) written to {} and checkpoint.h5", solver.step_count(),
                               solver.time(), frame);
      }
    } catch (const Error& io) {
      message += fmt::format(" | the last good state could not be written: {}", io.what());
    }
    throw instability_error(message);
  };

  const std::int64_t first_step = solver.step_count();
  const auto start = std::chrono::steady_clock::now();
  auto last_progress = start;
  const bool tty = isatty(fileno(stderr));
  auto elapsed = [&]() { return std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count(); };
  SignalCatcher signals(options.handle_signals);

  solver.record_work(options.recorder);
  double solver_seconds = 0.0;  // with a recorder: the steps' time, the rest of the loop apart
  while (!solver.finished()) {
    bool wrote = false, snapshot_due = false;
    const std::size_t recorded_before = options.recorder ? options.recorder->steps().size() : 0;
    const auto step_start = std::chrono::steady_clock::now();
    auto step_end = step_start;
    try {
      solver.step();
      step_end = std::chrono::steady_clock::now();
      const bool last = solver.finished();
      if (scene.output.history_interval <= 0.0 || solver.time() >= progress.next_history || last) {
        ScopedPhase timer(solver.phase_times(), Phase::Output);
        const EnergyBudget e = solver.energies();
        write_history(e);
        write_runout();
        while (scene.output.history_interval > 0.0 && progress.next_history <= solver.time())
          progress.next_history += scene.output.history_interval;
        energy_guard.check(e, solver.particles(), scene, solver.step_count(), solver.time());
      }
      const bool frame_due = (scene.output.frame_interval > 0.0 && solver.time() >= progress.next_frame) || last;
      const bool checkpoint_due =
          scene.output.checkpoint_interval > 0.0 && solver.time() >= progress.next_checkpoint && !last;
      snapshot_due = frame_due || checkpoint_due ||
                     (snapshot_interval > 0 && solver.step_count() - last_snapshot_step >= snapshot_interval);
      // What is written or kept as the last good state is checked in every field first (the solver
      // scans them only every few steps, stability_guards.hpp).
      if (snapshot_due) solver.check_particles();
      if (frame_due) {
        write_frame();
        while (scene.output.frame_interval > 0.0 && progress.next_frame <= solver.time())
          progress.next_frame += scene.output.frame_interval;
        wrote = true;
      }
      if (checkpoint_due) {
        while (progress.next_checkpoint <= solver.time()) progress.next_checkpoint += scene.output.checkpoint_interval;
        write_checkpoint_now();
        wrote = true;
      }
    } catch (const Error& e) {
      if (e.kind() != Error::Kind::Instability) throw;
      fail(e);
    }
    // The snapshot never predates a frame or checkpoint, so the failure path writes in order.
    if (wrote || snapshot_due) take_snapshot();
    if (const int sig = signals.caught(); sig != 0 && !solver.finished()) {
      write_checkpoint_now();
      summary.interrupted_signal = sig;
      break;
    }
    const auto now = std::chrono::steady_clock::now();
    if (options.recorder) {
      solver_seconds += std::chrono::duration<double>(step_end - step_start).count();
      if (options.recorder->steps().size() > recorded_before)
        options.recorder->add_after_step("output and guards", std::chrono::duration<double>(now - step_end).count());
    }
    const bool last = solver.finished();
    if (options.progress && (std::chrono::duration<double>(now - last_progress).count() >= options.progress_seconds || last)) {
      last_progress = now;
      const double wall = elapsed();
      const double fraction = scene.max_steps > 0
                                  ? std::max(solver.time() / scene.end_time, double(solver.step_count()) / scene.max_steps)
                                  : solver.time() / scene.end_time;
      const double rate = (solver.step_count() - first_step) * double(solver.particles().size()) / std::max(wall, 1e-9);
      fmt::print(stderr, "{}talus: step {:>8}  t = {:.4g}/{:.4g} s ({:5.1f}%)  dt = {:.3e} s  {:.2f} M particle-updates/s  ETA {}{}",
                 tty ? "\r" : "", solver.step_count(), solver.time(), scene.end_time, 100.0 * fraction, solver.last_dt(),
                 rate / 1e6, format_duration(wall * (1.0 - fraction) / std::max(fraction, 1e-12)), tty ? "   " : "\n");
      if (tty && last) fmt::print(stderr, "\n");
    }
  }
  history.flush();
  if (runout && runout->has_samples()) {
    summary.runout = runout->result();
    summary.runout_summary_path = (dir / "runout.json").string();
    write_file_atomically(summary.runout_summary_path, runout_result_json(*summary.runout, solver.time()) + "\n");
    if (solver.finished()) {  // the deposit of a completed run (not of one stopped by a signal)
      ScopedPhase timer(solver.phase_times(), Phase::Output);
      const FlumeCoordinates& c = runout->coordinates();
      const GridGeometry& g = scene.grid;
      const double x1 = g.origin[0] + g.cells[0] * g.h;
      const DepositRaster deposit = measure_deposit(solver.particles(), c, c.s(g.origin[0]), c.s(x1), g.origin[1],
                                                    g.origin[1] + g.cells[1] * g.h, scene.runout.deposit_cell);
      summary.deposit_path = (dir / "deposit.csv").string();
      write_deposit_csv(summary.deposit_path, deposit, c);
    }
  }
  summary.steps = solver.step_count();
  summary.time = solver.time();
  summary.wall_seconds = elapsed();
  if (options.recorder) {
    options.recorder->set_totals(solver.step_count() - first_step, solver_seconds, summary.wall_seconds - solver_seconds);
    solver.record_work(nullptr);
  }
  summary.final = solver.energies();
  return summary;
}

}  // namespace talus
