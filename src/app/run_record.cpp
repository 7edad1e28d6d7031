#include "run_record.hpp"

#include "build_info.hpp"
#include "commands.hpp"
#include "host_info.hpp"
#include "talus/core/simd_dispatch.hpp"
#include "talus/io/atomic_file.hpp"
#include "talus/solver/work_recorder.hpp"

#include <fmt/core.h>
#include <omp.h>


#include <algorithm>
#include <ctime>
#include <fstream>

namespace talus::app {

namespace fs = std::filesystem;

namespace {

/// A JSON object of the project's helpers as a member of the record (whose keys keep their order).
nlohmann::ordered_json ordered(const nlohmann::json& object) { return nlohmann::ordered_json::parse(object.dump()); }

std::string absolute(const std::string& path) {
  std::error_code ec;
  const fs::path p = fs::absolute(path, ec);
  return ec ? path : p.lexically_normal().string();
}

/// The parts of a run before a resumed one: the record in the checkpoint's folder, with its own
/// earlier parts before it. A part that still says "running" ended without finishing its record.
nlohmann::ordered_json earlier_parts(const fs::path& folder) {
  std::ifstream in(folder / "run.json");
  if (!in) return nlohmann::ordered_json::array();
  nlohmann::ordered_json last = nlohmann::ordered_json::parse(in, nullptr, /*allow_exceptions=*/false);
  if (!last.is_object()) return nlohmann::ordered_json::array();  // not a record of ours: left out
  nlohmann::ordered_json parts = last.contains("earlier_parts") && last["earlier_parts"].is_array() ? last["earlier_parts"]
                                                                                           : nlohmann::ordered_json::array();
  last.erase("earlier_parts");
  if (last.value("status", "") == "running") {
    last["status"] = "ended_unrecorded";
    last["message"] = "this part ended without finishing its record (killed, or its machine stopped)";
  }
  parts.push_back(std::move(last));
  return parts;
}

}  // namespace

RunRecord::RunRecord(const fs::path& dir, const Solver& solver, const RunStart& start, const Comm& comm)
    : path_(dir / "run.json"), comm_(comm), started_(start.clock_start) {
  const Scene& scene = solver.scene();
  record_["record_version"] = 1;
  record_["status"] = "running";
  record_["message"] = "";  // (here, beside the status, for every end that says something)
  record_["talus"] = ordered(build_json());
  record_["command"] = command_line();
  std::error_code ec;
  record_["working_directory"] = fs::current_path(ec).string();
  record_["scene"] = {{"name", scene.name}, {"file", absolute(start.scene_path)}, {"resolved", "scene.json"}};
  // the frames' `body` point array holds indices: entry i names body i (as the frames' field data)
  record_["body_names"] = body_names(scene);
  if (!start.restart_path.empty()) {
    record_["restart"] = {{"checkpoint", absolute(start.restart_path)}, {"step", solver.step_count()},
                          {"time", solver.time()}};
    if (!start.restart_changes.empty()) record_["restart"]["changed"] = start.restart_changes;
    std::string folder = fs::path(start.restart_path).parent_path().string();
    record_["earlier_parts"] = earlier_parts(folder.empty() ? "." : folder);
  }
  // (the CPUs of the host, and those this process may run on: under mpirun's binding or taskset the
  // one figure that was recorded, OpenMP's, said 1 on a 2-CPU host)
  record_["host"] = host_json();
  record_["ranks"] = comm.size();
  record_["threads"] = omp_get_max_threads();
  record_["isa"] = active_isa();
  record_["openmp"] = ordered(WorkRecorder::openmp_settings());
  record_["started"] = utc_text(start.utc_start);
  record_["start"] = {{"step", solver.step_count()}, {"time", solver.time()}, {"particles", start.particles},
                      {"estimated_memory_bytes", start.estimated_bytes}};
  record_["end_time"] = scene.end_time;
  // Rank 0 writes; a record it cannot write (a full disk) stops every rank alike, before the run.
  std::string problem;
  if (comm_.root()) try {
      write();
    } catch (const Error& e) {
      problem = e.what();
    }
  const bool failed = comm_.distributed() ? comm_.allgather(int(!problem.empty()))[0] != 0 : !problem.empty();
  if (failed) throw io_error(problem.empty() ? "cannot write " + path_.string() + " (rank 0)" : problem);
}

void RunRecord::progress(const Solver& solver) {
  record_["progress"] = {{"step", solver.step_count()}, {"time", solver.time()}, {"updated", utc_text(std::time(nullptr))}};
  if (!comm_.root()) return;
  try {
    write();
  } catch (const Error&) {
    // (a full disk: the frames meet it too, and stop the run with their own error)
  }
}

void RunRecord::end_common(const Solver& solver, std::string_view status, const std::string& message) {
  record_["status"] = std::string(status);
  record_["message"] = message;
  record_.erase("progress");  // ("end" says where it ended)
  record_["finished"] = utc_text(std::time(nullptr));
  record_["wall_seconds"] = std::chrono::duration<double>(std::chrono::steady_clock::now() - started_).count();
  record_["end"] = {{"step", solver.step_count()}, {"time", solver.time()}};
  if (energy_warning_)  // where the growth first passed guards.energy_warning_factor
    record_["end"]["energy_growth_warning"] = {{"step", energy_warning_->step},
                                               {"time", energy_warning_->time},
                                               {"share_of_energy_available", energy_warning_->share}};
  // (this process's: rank 0's in a distributed run, or the rank that failed)
  record_["peak_resident_bytes"] = peak_rss_bytes();
}

void RunRecord::end(const Solver& solver, const RunSummary& summary, const RunEnd& counts) {
  if (summary.energy_warning) energy_warning_ = summary.energy_warning;
  const bool interrupted = summary.interrupted_signal != 0 || summary.stopped_at_deadline;
  end_common(solver, interrupted ? "interrupted" : "completed",
             summary.stopped_at_deadline ? "stopped at its --stop-after time after writing a checkpoint"
             : interrupted ? fmt::format("stopped by signal {} after writing a checkpoint", summary.interrupted_signal)
             : solver.stopped_at_max_steps()
                 ? fmt::format("stopped at time.max_steps = {}, at t = {:.6g} s of time.end = {:.6g} s",
                               solver.scene().max_steps, solver.time(), solver.scene().end_time)
                 : "");
  nlohmann::ordered_json& end = record_["end"];
  end["particles"] = counts.particles;
  end["steps_this_part"] = summary.steps - summary.first_step;
  // (the seconds of the stepping loop, frames included, that the closing line's rate divides by;
  // the record's wall_seconds adds the setup before it and the closing outputs after it)
  end["stepping_wall_seconds"] = summary.wall_seconds;
  end["particle_updates_per_second"] = summary.wall_seconds > 0.0 ? summary.particle_updates / summary.wall_seconds : 0.0;
  end["frames_in_series"] = summary.frames_in_series;
  if (interrupted) {
    end["checkpoint"] = summary.checkpoint_path;
  } else {
    if (solver.emptied()) end["every_particle_left"] = true;
    // as the run's last lines print it: of the energy available, and the two in joules
    end["energy_budget_gap"] = summary.energy_budget_gap();
    end["energy_budget_gap_joules"] = summary.energy_budget_gap_joules();
    end["energy_available_joules"] = summary.energy_scale();
  }
  end["outflow_particles"] = counts.outflow_particles;
  // Where they left: each open face's particles and mass (a face that is not open lets nothing out)
  nlohmann::ordered_json by_face = nlohmann::ordered_json::object();
  for (int face = 0; face < OutflowFaces::kFaces; ++face)
    if (solver.scene().walls[face / 2][face % 2].type == WallType::Open)
      by_face[OutflowFaces::kNames[face]] = {{"particles", counts.outflow_by_face.particles[face]},
                                             {"mass_kg", counts.outflow_by_face.mass[face]}};
  end["outflow_by_face"] = std::move(by_face);
  if (comm_.root()) write();
}

void RunRecord::end_with_error(const Solver& solver, const Error& error) {
  // (one every rank has: rank 0 records it, and its message names the rank that failed)
  if (error.agreed() && comm_.distributed() && !comm_.root()) return;
  end_after_error(solver, error.kind() == Error::Kind::Instability ? "unstable" : "failed", error.what(),
                  !error.agreed());
}

void RunRecord::end_with_error(const Solver& solver, const std::exception& error) {
  end_after_error(solver, "failed", fmt::format("internal error: {}", error.what()), true);
}

void RunRecord::end_after_error(const Solver& solver, std::string_view status, const std::string& message,
                                bool this_ranks) {
  end_common(solver, status, message);
  if (comm_.distributed() && this_ranks) record_["end"]["rank"] = comm_.rank();
  try {
    write();
  } catch (const Error&) {
    // (the run's own error is the one to report: a record that cannot be written, on a full disk
    // say, keeps its "running")
  }
}

void RunRecord::write() const { write_file_atomically(path_.string(), record_.dump(2) + "\n"); }

}  // namespace talus::app
