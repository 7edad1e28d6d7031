#include "talus/io/run_driver.hpp"

#include "talus/core/error.hpp"
#include "talus/io/vtu_writer.hpp"
#include "talus/scene/scene_json.hpp"

#include <fmt/core.h>
#include <unistd.h>

#include <chrono>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>

namespace talus {

namespace fs = std::filesystem;

namespace {

void prepare_output_folder(const std::string& dir) {
  std::error_code ec;
  fs::create_directories(fs::path(dir) / "frames", ec);
  if (ec) throw io_error(fmt::format("cannot create output folder {}: {}", dir, ec.message()));
  // Replace the outputs of an earlier run in the same folder, so no stale frame survives.
  for (const auto& entry : fs::directory_iterator(fs::path(dir) / "frames"))
    if (entry.path().extension() == ".vtu") fs::remove(entry.path());
  for (const char* f : {"particles.pvd", "energy.csv", "scene.json"}) fs::remove(fs::path(dir) / f, ec);
}

std::string format_duration(double seconds) {
  if (!std::isfinite(seconds) || seconds < 0) return "?";
  const long s = std::lround(seconds);
  if (s >= 3600) return fmt::format("{}h{:02}m", s / 3600, (s / 60) % 60);
  if (s >= 60) return fmt::format("{}m{:02}s", s / 60, s % 60);
  return fmt::format("{}s", s);
}

}  // namespace

RunSummary run_scene(Solver& solver, const RunOptions& options) {
  const Scene& scene = solver.scene();
  const fs::path dir(options.out_dir);
  prepare_output_folder(options.out_dir);
  write_file_atomically((dir / "scene.json").string(), scene_to_json(scene).dump(2) + "\n");

  RunSummary summary;
  summary.pvd_path = (dir / "particles.pvd").string();
  PvdIndex pvd(summary.pvd_path);
  std::ofstream history(dir / "energy.csv");
  if (!history) throw io_error(fmt::format("cannot write {}", (dir / "energy.csv").string()));
  history << "time,step,dt,kinetic,strain,gravity,friction_work,plastic_work,total\n";

  auto write_history = [&](const EnergyBudget& e) {
    history << fmt::format("{:.10e},{},{:.6e},{:.10e},{:.10e},{:.10e},{:.10e},{:.10e},{:.10e}\n", solver.time(),
                           solver.step_count(), solver.last_dt(), e.kinetic, e.strain, e.gravity, e.friction_work,
                           e.plastic_work, e.total());
  };
  auto write_frame = [&]() {
    ScopedPhase timer(solver.phase_times(), Phase::Output);
    const std::string name = fmt::format("frames/particles_{:06}.vtu", summary.frames);
    write_particles_vtu((dir / name).string(), solver.particles(), scene.output.compress);
    pvd.add(solver.time(), name);
    ++summary.frames;
    history.flush();
  };

  summary.initial = solver.energies();
  write_history(summary.initial);
  write_frame();
  double next_frame = scene.output.frame_interval;
  double next_history = scene.output.history_interval;

  const auto start = std::chrono::steady_clock::now();
  auto last_progress = start;
  const bool tty = isatty(fileno(stderr));
  auto elapsed = [&]() { return std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count(); };

  while (!solver.finished()) {
    solver.step();
    const bool last = solver.finished();
    if (scene.output.history_interval <= 0.0 || solver.time() >= next_history || last) {
      ScopedPhase timer(solver.phase_times(), Phase::Output);
      write_history(solver.energies());
      while (scene.output.history_interval > 0.0 && next_history <= solver.time()) next_history += scene.output.history_interval;
    }
    if ((scene.output.frame_interval > 0.0 && solver.time() >= next_frame) || last) {
      write_frame();
      while (scene.output.frame_interval > 0.0 && next_frame <= solver.time()) next_frame += scene.output.frame_interval;
    }
    const auto now = std::chrono::steady_clock::now();
    if (options.progress && (std::chrono::duration<double>(now - last_progress).count() >= options.progress_seconds || last)) {
      last_progress = now;
      const double wall = elapsed();
      const double fraction = scene.max_steps > 0
                                  ? std::max(solver.time() / scene.end_time, double(solver.step_count()) / scene.max_steps)
                                  : solver.time() / scene.end_time;
      const double rate = solver.step_count() * double(solver.particles().size()) / std::max(wall, 1e-9);
      fmt::print(stderr, "{}talus: step {:>8}  t = {:.4g}/{:.4g} s ({:5.1f}%)  dt = {:.3e} s  {:.2f} M particle-updates/s  ETA {}{}",
                 tty ? "\r" : "", solver.step_count(), solver.time(), scene.end_time, 100.0 * fraction, solver.last_dt(),
                 rate / 1e6, format_duration(wall * (1.0 - fraction) / std::max(fraction, 1e-12)), tty ? "   " : "\n");
      if (tty && last) fmt::print(stderr, "\n");
    }
  }
  history.flush();
  summary.steps = solver.step_count();
  summary.time = solver.time();
  summary.wall_seconds = elapsed();
  summary.final = solver.energies();
  return summary;
}

}  // namespace talus
