#include "talus/driver/run_outputs.hpp"

#include "talus/core/error.hpp"
#include "talus/io/runout_output.hpp"
#include "talus/particles/particle_migration.hpp"

#include <fmt/core.h>

#include <algorithm>
#include <cstdio>

namespace talus {

namespace fs = std::filesystem;

namespace {

void remove_temporaries(const fs::path& dir) {
  std::error_code ec;
  for (const fs::path& d : {dir, dir / "frames"})
    for (const auto& entry : fs::directory_iterator(d, ec))
      if (entry.path().extension() == ".tmp") fs::remove(entry.path(), ec);
}

/// The columns of energy.csv: time, step, dt, one per term of the energy ledger, then the total.
std::string energy_header() {
  std::string header = "time,step,dt";
  const EnergyBudget names;
  EnergyBudget::for_each_term(names, [&](const char* name, double, bool) { header += std::string(",") + name; });
  return header + ",total";
}

/// Rewrite a CSV file (atomically) with its header and the rows `keep` accepts, up to the first it
/// refuses; returns the number of rows kept.
template <class Keep>
std::size_t cut_csv(const fs::path& path, const std::string& header, Keep keep) {
  std::string kept = header + "\n";
  std::ifstream in(path);
  std::string line;
  std::getline(in, line);  // the old header
  std::size_t rows = 0;
  while (std::getline(in, line) && keep(line)) {
    kept += line + "\n";
    ++rows;
  }
  in.close();
  write_file_atomically(path.string(), kept);
  return rows;
}

}  // namespace

std::string frame_name(std::size_t index) { return fmt::format("frames/particles_{:06}.vtu", index); }

void prepare_output_folder(const fs::path& dir, const RunProgress* resume) {
  std::error_code ec;
  fs::create_directories(dir / "frames", ec);
  if (ec) throw io_error(fmt::format("cannot create output folder {}: {}", dir.string(), ec.message()));
  remove_temporaries(dir);
  for (const auto& entry : fs::directory_iterator(dir / "frames")) {
    if (entry.path().extension() != ".vtu") continue;
    // A resumed run keeps the frames its checkpoint lists.
    unsigned long index = 0;
    const std::string name = entry.path().filename().string();
    const bool listed = resume && std::sscanf(name.c_str(), "particles_%lu.vtu", &index) == 1 &&
                        index < resume->frame_times.size();
    if (!listed) fs::remove(entry.path(), ec);
  }
  if (resume) return;
  for (const char* f : {"particles.pvd", "energy.csv", "scene.json", "checkpoint.h5", "runout.csv", "runout.json",
                        "deposit.csv", "terrain.vtu"})
    fs::remove(dir / f, ec);
}

// ---- energy.csv ---------------------------------------------------------------------------------

EnergyHistory::EnergyHistory(const fs::path& dir, std::optional<std::int64_t> resume_step, bool writer)
    : writer_(writer) {
  if (!writer_) return;
  const fs::path path = dir / "energy.csv";
  const std::string header = energy_header();
  if (resume_step) {
    // Keep the complete rows (time,step,...) up to the checkpoint's step.
    const auto commas = std::count(header.begin(), header.end(), ',');
    cut_csv(path, header, [&](const std::string& line) {
      const auto c1 = line.find(',');
      const auto c2 = c1 == std::string::npos ? std::string::npos : line.find(',', c1 + 1);
      if (c2 == std::string::npos || std::count(line.begin(), line.end(), ',') != commas) return false;
      try {
        return std::stoll(line.substr(c1 + 1, c2 - c1 - 1)) <= *resume_step;
      } catch (const std::exception&) {
        return false;
      }
    });
  }
  file_.open(path, resume_step ? std::ios::app : std::ios::trunc);
  if (!file_) throw io_error(fmt::format("cannot write {}", path.string()));
  if (!resume_step) file_ << header << "\n";
}

void EnergyHistory::write(const Solver& solver, const EnergyBudget& e) {
  if (!writer_) return;
  std::string row = fmt::format("{:.10e},{},{:.6e}", solver.time(), solver.step_count(), solver.last_dt());
  EnergyBudget::for_each_term(e, [&](const char*, double value, bool) { row += fmt::format(",{:.10e}", value); });
  file_ << row << fmt::format(",{:.10e}\n", e.total());
  file_.flush();
}

// ---- runout.csv, runout.json, deposit.csv -------------------------------------------------------

RunoutFiles::RunoutFiles(const Scene& scene, const fs::path& dir, std::optional<std::int64_t> resume_step,
                         const Comm& comm)
    : scene_(scene), dir_(dir), comm_(comm) {
  if (!scene.runout.enabled) return;
  monitor_.emplace(scene.runout, flume_coordinates_of(scene));
  history_path_ = (dir / "runout.csv").string();
  if (!comm_.root()) return;  // rank 0 measures and writes
  if (resume_step) {
    // Keep the rows up to the checkpoint's step; the monitor continues from the first and last.
    std::optional<RunoutSample> first, last;
    cut_csv(history_path_, runout_csv_header(), [&](const std::string& line) {
      const auto row = parse_runout_csv_row(line);
      if (!row || row->step > *resume_step) return false;
      if (!first) first = row;
      last = row;
      return true;
    });
    if (first) monitor_->resume(*first, *last);
  }
  file_.open(history_path_, resume_step ? std::ios::app : std::ios::trunc);
  if (!file_) throw io_error(fmt::format("cannot write {}", history_path_));
  if (!resume_step) file_ << runout_csv_header() << "\n";
}

void RunoutFiles::write(const Solver& solver) {
  if (!monitor_) return;
  const ParticleStore all = gather_particles(comm_, solver.particles());
  if (!comm_.root()) return;
  file_ << runout_csv_row(monitor_->sample(all, solver.time(), solver.step_count())) << "\n";
  file_.flush();
}

RunoutFiles::Outcome RunoutFiles::finish(Solver& solver) const {
  Outcome out;
  if (!monitor_) return out;
  // the deposit needs every particle on rank 0 (collective: every rank takes part)
  const bool completed = solver.finished();
  const ParticleStore all = completed ? gather_particles(comm_, solver.particles()) : ParticleStore();
  if (!comm_.root() || !monitor_->has_samples()) return out;
  out.result = monitor_->result();
  out.summary_path = (dir_ / "runout.json").string();
  write_file_atomically(out.summary_path, runout_result_json(*out.result, solver.time()) + "\n");
  if (!completed) return out;  // the deposit of a completed run (not of one stopped by a signal)
  ScopedPhase timer(solver.phase_times(), Phase::Output);
  const FlumeCoordinates& c = monitor_->coordinates();
  const GridGeometry& g = scene_.grid;
  const double x1 = g.origin[0] + g.cells[0] * g.h;
  const DepositRaster deposit = measure_deposit(all, c, c.s(g.origin[0]), c.s(x1), g.origin[1],
                                                g.origin[1] + g.cells[1] * g.h, scene_.runout.deposit_cell);
  out.deposit_path = (dir_ / "deposit.csv").string();
  write_deposit_csv(out.deposit_path, deposit, c);
  return out;
}

// ---- frames and the ParaView series -------------------------------------------------------------

FrameSeries::FrameSeries(const fs::path& dir, bool compress, RunProgress& progress)
    : dir_(dir), compress_(compress), progress_(progress), pvd_path_((dir / "particles.pvd").string()), pvd_(pvd_path_) {
  std::vector<std::pair<double, std::string>> entries;
  for (std::size_t i = 0; i < progress.frame_times.size(); ++i) entries.emplace_back(progress.frame_times[i], frame_name(i));
  if (!entries.empty()) pvd_.assign(std::move(entries));
}

std::string FrameSeries::write(Solver& solver) {
  ScopedPhase timer(solver.phase_times(), Phase::Output);
  const std::string name = frame_name(progress_.frame_times.size());
  write_particles_vtu((dir_ / name).string(), solver.particles(), compress_);
  pvd_.add(solver.time(), name);
  progress_.frame_times.push_back(solver.time());
  progress_.frame_steps.push_back(solver.step_count());
  return name;
}

bool FrameSeries::has_frame_of_step(std::int64_t step) const {
  return !progress_.frame_steps.empty() && progress_.frame_steps.back() == step;
}

// ---- checkpoint.h5 ------------------------------------------------------------------------------

void CheckpointFile::write(Solver& solver, const RunProgress& progress) {
  ScopedPhase timer(solver.phase_times(), Phase::Output);
  write_checkpoint(path_, solver, progress);
}

}  // namespace talus
