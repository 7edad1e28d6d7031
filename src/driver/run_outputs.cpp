#include "talus/driver/run_outputs.hpp"
#include "talus/driver/warning.hpp"

#include "talus/core/error.hpp"
#include "talus/io/atomic_file.hpp"
#include "talus/io/runout_output.hpp"
#include "talus/particles/particle_migration.hpp"

#include <fmt/core.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <memory>
#include <optional>
#include <regex>
#include <utility>

#include <unistd.h>

namespace talus {

namespace fs = std::filesystem;

namespace {

void remove_temporaries(const fs::path& dir) {
  std::error_code ec;
  for (const fs::path& d : {dir, dir / "frames"})
    for (const auto& entry : fs::directory_iterator(d, ec))
      if (entry.path().extension() == ".tmp") fs::remove(entry.path(), ec);
}

/// The index of a frame file: frames/particles_<i>.vtu, particles_<i>.pvtu or a rank's piece
/// particles_<i>_<rank>.vtu; nothing for any other name.
std::optional<unsigned long> frame_index(const std::string& file_name) {
  static const std::regex pattern(R"(particles_([0-9]+)(_[0-9]+)?\.(vtu|pvtu))");
  std::smatch match;
  if (!std::regex_match(file_name, match, pattern) || (match[2].matched && match[3] != "vtu")) return std::nullopt;
  try {
    return std::stoul(match[1].str());
  } catch (const std::exception&) {
    return std::nullopt;  // an index past unsigned long: no frame of ours
  }
}

/// prepare_output_folder on the rank that deletes.
void clear_output_folder(const fs::path& dir, const RunProgress* resume) {
  std::error_code ec;
  fs::create_directories(dir / "frames", ec);
  if (ec) throw io_error(fmt::format("cannot create output folder {}: {}", (dir / "frames").string(), ec.message()));
  // A frames folder that exists but cannot be written: said here, once, instead of VTK's twenty lines
  // at the first frame after the run's other files were started
  if (::access((dir / "frames").c_str(), W_OK | X_OK) != 0)
    throw io_error(fmt::format("cannot write output folder {}: no write permission", (dir / "frames").string()));
  remove_temporaries(dir);
  for (const auto& entry : fs::directory_iterator(dir / "frames")) {
    const fs::path ext = entry.path().extension();
    if (ext != ".vtu" && ext != ".pvtu") continue;
    // A resumed run keeps the frames its checkpoint lists, whatever their kind.
    const std::optional<unsigned long> index = frame_index(entry.path().filename().string());
    if (!index) continue;  // not a frame of ours (a user's mesh.vtu stays)
    const bool listed = resume && *index < resume->frame_times.size();
    if (!listed) fs::remove(entry.path(), ec);
  }
  if (resume) {
    // The end of the part before (a run extended by a later time.end, or one resumed after it was
    // stopped or went unstable): until this part writes its own, a deposit.csv and a runout.json
    // "final" there described an end the run no longer has.
    for (const char* f : {"deposit.csv", "runout.json"}) fs::remove(dir / f, ec);
    return;
  }
  for (const fs::path& f : run_output_files(dir)) fs::remove(f, ec);
}

}  // namespace

std::vector<fs::path> run_output_files(const fs::path& dir) {
  std::vector<fs::path> files;
  for (const char* f : {"particles.pvd", "energy.csv", "scene.json", "checkpoint.h5", "checkpoint_earlier.h5",
                        "runout.csv", "runout.json",
                        "deposit.csv", "terrain.vtu", "run.json"})
    files.push_back(dir / f);
  return files;
}

std::size_t frames_by_interval(const Scene& scene) {
  const double interval = scene.output.frame_interval;
  if (interval <= 0.0) return 2;
  // (a frame falls on the first step at or past each multiple, and the last step writes one unless
  // it was such a step: 1 + ceil(end / interval), less a rounding margin when end is a multiple)
  const double frames = 1.0 + std::ceil(scene.end_time / interval * (1.0 - 1e-12));
  // (none takes 10^15 steps: the cap keeps a vanishing interval, 1e-300 s, from overflowing the count)
  constexpr double kMostFrames = 1e15;
  return static_cast<std::size_t>(std::min(frames, kMostFrames));
}

double estimated_steps(const Scene& scene) {
  const double steps = std::ceil(scene.end_time / scene.initial_time_step() * (1.0 - 1e-12));
  return scene.max_steps > 0 ? std::min(steps, double(scene.max_steps)) : steps;
}

std::size_t frames_of_run(const Scene& scene) {
  // A run writes at most one frame a step, the first at step 0: with an interval shorter than the
  // step (end 1 s, frame_interval 1e-5 s: 100 001 frames by the interval, 227 written), the steps
  // bound the count; they are estimated at the initial time step (a flow that speeds up takes more).
  const std::size_t by_interval = frames_by_interval(scene);
  const double by_steps = estimated_steps(scene) + 1.0;
  return by_steps < double(by_interval) ? static_cast<std::size_t>(by_steps) : by_interval;
}

bool same_file(const fs::path& a, const fs::path& b) {
  std::error_code ec;
  if (fs::exists(a, ec) && fs::exists(b, ec)) return fs::equivalent(a, b, ec);
  const fs::path ca = fs::weakly_canonical(fs::absolute(a, ec), ec), cb = fs::weakly_canonical(fs::absolute(b, ec), ec);
  return ca == cb;
}

namespace {

/// The file of frame i of a resumed series: the kind this run writes, unless only the other kind
/// is on disk (a run resumed with another number of ranks keeps its earlier frames).
std::string kept_frame_name(const fs::path& dir, std::size_t index, bool distributed) {
  const std::string own = frame_name(index, distributed);
  const std::string other = frame_name(index, !distributed);
  std::error_code ec;
  return !fs::exists(dir / own, ec) && fs::exists(dir / other, ec) ? other : own;
}

/// The columns of energy.csv: time, step, dt, one per term of the energy ledger, then the total, then
/// (output.energy_gap_terms) what the budget's gap is made of.
std::string energy_header(bool gap_terms) {
  std::string header = "time,step,dt";
  const EnergyBudget names;
  EnergyBudget::for_each_term(names, [&](const char* name, double, bool) { header += std::string(",") + name; });
  header += ",total";
  const EnergyGapTerms gap_names;
  if (gap_terms) EnergyGapTerms::for_each_term(gap_names, [&](const char* name, double) { header += std::string(",") + name; });
  return header;
}

/// Rewrite a CSV file (atomically) with its header and the rows `keep` accepts, up to the first it
/// refuses (keep(line) gives the row to write, or nothing); returns the number of rows kept.
template <class Keep>
std::size_t cut_csv(const fs::path& path, const std::string& header, Keep keep) {
  std::string kept = header + "\n";
  std::ifstream in(path);
  std::string line;
  std::getline(in, line);  // the old header
  std::size_t rows = 0;
  while (std::getline(in, line)) {
    const std::optional<std::string> row = keep(line);
    if (!row) break;
    kept += *row + "\n";
    ++rows;
  }
  in.close();
  write_file_atomically(path.string(), kept);
  return rows;
}

}  // namespace

namespace {

/// `relative` taken from `base`, without the trailing separator that "." leaves ("a/." is "a/").
fs::path folder_from(const fs::path& base, const std::string& relative) {
  fs::path folder = (base / relative).lexically_normal();
  if (!folder.has_filename() && folder.has_relative_path()) folder = folder.parent_path();
  return folder;
}

}  // namespace

fs::path frame_folder(const RunProgress& progress, std::size_t index, const fs::path& dir) {
  fs::path folder = dir;
  for (const auto& [first, path] : progress.frame_folders)
    if (first <= index) folder = folder_from(dir, path);
  return folder;
}

void record_frame_folder(RunProgress& progress, const fs::path& dir, const fs::path& resume_dir) {
  const fs::path here = folder_from(fs::absolute(dir), ".");
  if (!resume_dir.empty()) {
    // the earlier parts' folders, now relative to this one (those of a checkpoint that did not
    // keep them: its own folder)
    const fs::path there = folder_from(fs::absolute(resume_dir), ".");
    if (progress.frame_folders.empty()) progress.frame_folders.emplace_back(0, ".");
    for (auto& [first, path] : progress.frame_folders) path = folder_from(there, path).lexically_relative(here).string();
  }
  progress.frame_folders.emplace_back(progress.frame_times.size(), ".");
}

std::string frame_name(std::size_t index, bool distributed) {
  return fmt::format("frames/particles_{:06}.{}", index, distributed ? "pvtu" : "vtu");
}

std::string frame_piece_name(std::size_t index, int rank) {
  return fmt::format("frames/particles_{:06}_{:04}.vtu", index, rank);
}

void prepare_output_folder(const fs::path& dir, const RunProgress* resume, const Comm& comm) {
  if (!comm.distributed()) {
    clear_output_folder(dir, resume);
    return;
  }
  // Rank 0 alone deletes (the ranks share the folder); its error, if any, reaches every rank, so
  // all stop alike. The broadcast is the barrier: no rank returns before rank 0 is done.
  std::string error;
  if (comm.root()) {
    try {
      clear_output_folder(dir, resume);
    } catch (const std::exception& e) {
      error = e.what();
      if (error.empty()) error = fmt::format("cannot prepare output folder {}", dir.string());
    }
  }
  error = comm.broadcast(error);
  if (!error.empty()) throw io_error(error);
}

// ---- energy.csv ---------------------------------------------------------------------------------

EnergyHistory::EnergyHistory(const fs::path& dir, std::optional<std::int64_t> resume_step, bool writer, bool gap_terms)
    : writer_(writer), gap_terms_(gap_terms) {
  if (!writer_) return;
  const fs::path path = dir / "energy.csv";
  const std::string header = energy_header(gap_terms);
  if (resume_step) {
    // Keep the complete rows (time,step,...) up to the checkpoint's step.
    const auto commas = std::count(header.begin(), header.end(), ',');
    kept_rows_ = cut_csv(path, header, [&](const std::string& line) -> std::optional<std::string> {
      const auto c1 = line.find(',');
      const auto c2 = c1 == std::string::npos ? std::string::npos : line.find(',', c1 + 1);
      if (c2 == std::string::npos || std::count(line.begin(), line.end(), ',') != commas) return std::nullopt;
      try {
        if (std::stoll(line.substr(c1 + 1, c2 - c1 - 1)) <= *resume_step) return line;
      } catch (const std::exception&) {
      }
      return std::nullopt;
    });
  }
  file_.open(path, resume_step ? std::ios::app : std::ios::trunc);
  if (!file_) throw io_error(fmt::format("cannot write {}", path.string()));
  if (!resume_step) file_ << header << "\n";
}

void EnergyHistory::write(const Solver& solver, const EnergyBudget& e) {
  const EnergyGapTerms gap = gap_terms_ ? solver.energy_gap_terms() : EnergyGapTerms{};  // collective
  if (!writer_) return;
  // (the time to 17 digits, as runout.csv writes it: the two files' rows of one step join on it)
  std::string row = fmt::format("{:.17g},{},{:.6e}", solver.time(), solver.step_count(), solver.last_dt());
  EnergyBudget::for_each_term(e, [&](const char*, double value, bool) { row += fmt::format(",{:.10e}", value); });
  row += fmt::format(",{:.10e}", e.total());
  if (gap_terms_) EnergyGapTerms::for_each_term(gap, [&](const char*, double value) { row += fmt::format(",{:.10e}", value); });
  file_ << row << "\n";
  file_.flush();
}

// ---- runout.csv, runout.json, deposit.csv -------------------------------------------------------

RunoutFiles::RunoutFiles(const Scene& scene, const fs::path& dir, std::optional<std::int64_t> resume_step,
                         const Comm& comm, const fs::path& resume_dir, const std::string& saved_first_row)
    : scene_(scene), dir_(dir), comm_(comm) {
  if (!scene.runout.enabled) return;
  monitor_.emplace(scene.runout, flume_coordinates_of(scene), runout_grid_of(scene));
  history_path_ = (dir / "runout.csv").string();
  if (!comm_.root()) return;  // rank 0 measures and writes
  if (resume_step) {
    // The monitor continues from the first and last rows up to the checkpoint's step: the first
    // is the initial front (the default gate), the last the front velocity's difference.
    std::optional<RunoutSample> first, last;
    const FlumeCoordinates& coordinates = monitor_->coordinates();
    // A row read back: located again (a runout.csv written before front_x ... tail_z lacks them; the
    // row is then written with them, so the kept file has one header's columns), the same text otherwise.
    const auto read_row = [&](const std::string& line) {
      std::optional<RunoutSample> row = parse_runout_csv_row(line);
      if (row) locate_front_and_tail(*row, coordinates);
      return row;
    };
    const auto up_to_checkpoint = [&](const std::string& line) -> std::optional<std::string> {
      const auto row = read_row(line);
      if (!row || row->step > *resume_step) return std::nullopt;
      if (!first) first = row;
      last = row;
      return runout_csv_row(*row);
    };
    if (resume_dir.empty() || same_file(resume_dir, dir)) {
      cut_csv(history_path_, runout_csv_header(), up_to_checkpoint);  // keep those rows, drop later ones
    } else {
      // Resumed into another folder: the rows before the checkpoint stay in the checkpoint's
      // folder (read, not changed); this folder's history starts at the checkpoint. (Without
      // them the gate was the front at the checkpoint: 18% short on a flume.)
      std::ifstream before(resume_dir / "runout.csv");
      std::string line;
      std::getline(before, line);  // its header
      while (std::getline(before, line) && up_to_checkpoint(line)) {
      }
      write_file_atomically(history_path_, runout_csv_header() + "\n");
    }
    // Without a gate_x the runout is measured from the initial front, the first row: a folder
    // that lacks it (a resume of a resume into another folder, runout.csv removed) gave a runout
    // from a later front, 22% short, without a word. The checkpoint keeps that row; one written
    // before it did is resumed from the folder's first row, with a warning when that is not the start.
    const std::optional<RunoutSample> saved = saved_first_row.empty() ? std::nullopt : read_row(saved_first_row);
    if (saved) {
      first = saved;
      if (!last) last = saved;  // (the front velocity of the first row after the restart is then a mean)
    }
    if (first) monitor_->resume(*first, *last);
    if (!scene.runout.has_gate && (!first || first->step > 0))
      warn("{} lacks the runout rows from t = 0 (the initial front is the gate when "
           "diagnostics.runout.gate_x is not set): this run's runout is measured from {}; set gate_x, or "
           "resume in the folder that holds the rows from the start",
           ((resume_dir.empty() || same_file(resume_dir, dir) ? dir : resume_dir) / "runout.csv").string(),
           first ? fmt::format("the front at step {}", first->step) : std::string("the front at the restart"));
  }
  file_.open(history_path_, resume_step ? std::ios::app : std::ios::trunc);
  if (!file_) throw io_error(fmt::format("cannot write {}", history_path_));
  if (!resume_step) file_ << runout_csv_header() << "\n";
}

std::string RunoutFiles::first_row() const {
  return monitor_ && monitor_->has_samples() ? runout_csv_row(monitor_->first()) : std::string();
}

void RunoutFiles::write(const Solver& solver) {
  if (!monitor_) return;
  const AllParticles all(comm_, solver.particles());
  std::string row;
  if (comm_.root()) {
    row = runout_csv_row(monitor_->sample(all.get(), solver.time(), solver.step_count()));
    file_ << row << "\n";
    file_.flush();
  }
  if (!comm_.distributed()) return;
  // Every rank keeps the first and last rows, as written, and what had gone through open faces
  // then: a rank that an instability stops writes runout.json from them alone (finish_unstable).
  // (collective; nothing of the run's results changes)
  left_ = solver.outflow_mass();
  left_x_plus_ = solver.outflow_mass_x_plus();
  const std::string rows = comm_.broadcast(comm_.root() ? runout_csv_row(monitor_->first()) + "\n" + row : std::string());
  if (comm_.root()) return;
  const std::size_t cut = rows.find('\n');
  const auto first = parse_runout_csv_row(rows.substr(0, cut)), last = parse_runout_csv_row(rows.substr(cut + 1));
  if (first && last) monitor_->resume(*first, *last);
}

void RunoutFiles::finish_unstable() const {
  if (!monitor_ || !monitor_->has_samples()) return;
  RunoutResult r = monitor_->result();
  r.status = "unstable";
  r.final = false;
  const double total = monitor_->last().mass + left_;
  if (total > 0.0) {
    r.outflow_mass_share = left_ / total;
    r.outflow_mass_share_x_plus = left_x_plus_ / total;
  }
  r.limited_by_outflow = r.outflow_mass_share_x_plus > 1.0 - scene_.runout.front_quantile;
  write_file_atomically((dir_ / "runout.json").string(), runout_result_json(r) + "\n");
}

RunoutFiles::Outcome RunoutFiles::finish(Solver& solver, const std::string& status) const {
  Outcome out;
  if (!monitor_) return out;
  // every particle on rank 0: the deposit, and the state where a run stopped between history rows
  // (collective: every rank takes part)
  const AllParticles all(comm_, solver.particles());
  const double left = solver.outflow_mass(), left_x_plus = solver.outflow_mass_x_plus();  // (collective)
  if (!comm_.root() || !monitor_->has_samples()) return out;
  // A run stopped by a signal, --stop-after or an instability: its state where it stopped, which the
  // last history row is not (runout.json gave the row before the stop, and nothing said it was not
  // the end). A completed run's last row is of its last step.
  std::optional<RunoutSample> now;
  if (monitor_->last().step != solver.step_count()) now = monitor_->measure(all.get(), solver.time(), solver.step_count());
  out.result = monitor_->result(now ? &*now : nullptr);
  RunoutResult& r = *out.result;
  r.status = status;
  r.final = status == "completed" && !solver.stopped_at_max_steps() && !solver.emptied();
  // The front and tail are quantiles of the mass still in the grid: say how much had left, and
  // whether more left ahead of the front (x+) than the front quantile leaves there, so that the
  // whole flow's front lay beyond the grid (a slide run off the grid's end gave the grid's end as
  // its front, 1.5 m "beyond the gate", with 91% of its mass gone and not a word).
  const double total = (now ? *now : monitor_->last()).mass + left;
  if (total > 0.0) {
    r.outflow_mass_share = left / total;
    r.outflow_mass_share_x_plus = left_x_plus / total;
  }
  r.limited_by_outflow = r.outflow_mass_share_x_plus > 1.0 - scene_.runout.front_quantile;
  out.summary_path = (dir_ / "runout.json").string();
  write_file_atomically(out.summary_path, runout_result_json(*out.result) + "\n");
  // The deposit of a completed run: at its end time, at time.max_steps or once every particle left
  // (run.json's "completed"); not of one stopped before it completed.
  if (status != "completed") return out;
  ScopedPhase timer(solver.phase_times(), Phase::Output);
  const FlumeCoordinates& c = monitor_->coordinates();
  const GridGeometry& g = scene_.grid;
  const double x1 = g.origin[0] + g.cells[0] * g.h;
  const DepositRaster deposit = measure_deposit(all.get(), c, c.s(g.origin[0]), c.s(x1), g.origin[1],
                                                g.origin[1] + g.cells[1] * g.h, scene_.runout.deposit_cell);
  out.deposit_path = (dir_ / "deposit.csv").string();
  write_deposit_csv(out.deposit_path, deposit, c);
  return out;
}

// ---- frames and the ParaView series -------------------------------------------------------------

FrameSeries::FrameSeries(const fs::path& dir, bool compress, RunProgress& progress, const Comm& comm, bool background)
    : dir_(dir),
      compress_(compress),
      background_(background),
      progress_(progress),
      comm_(comm),
      pvd_path_((dir / "particles.pvd").string()),
      pvd_(pvd_path_, comm.root()) {
  // The index lists the checkpoint's earlier frames that are in this folder. A run resumed into
  // another folder (--restart with --out) has none of them there: listing them anyway gave a .pvd that
  // ParaView cannot open. Their indices stay taken, so the new frames do not reuse the names.
  // A frame written in another folder (a part resumed elsewhere, which the checkpoint records) is
  // not missing when it is there: resumed a second time, in the folder of a run resumed with --out,
  // the run warned that the series had gaps where the frames were in the first part's folder.
  std::vector<std::pair<double, std::string>> entries;
  for (std::size_t i = 0; i < progress.frame_times.size(); ++i) {
    std::string name = kept_frame_name(dir, i, comm.distributed());
    std::error_code ec;
    const fs::path written_in = frame_folder(progress, i, dir);
    if (fs::exists(dir / name, ec)) {
      entries.emplace_back(progress.frame_times[i], std::move(name));
    } else if (same_file(written_in, dir) || !fs::exists(written_in / kept_frame_name(written_in, i, comm.distributed()), ec)) {
      ++missing_kept_frames_;
      if (std::find(missing_from_.begin(), missing_from_.end(), written_in / "frames") == missing_from_.end())
        missing_from_.push_back(written_in / "frames");
    }
  }
  if (!entries.empty()) {
    kept_frames_in_older_order_ = frame_stress_in_vtk_order((dir / entries.back().second).string()) == false;
    pvd_.assign(std::move(entries));
  }
}

std::string FrameSeries::write(Solver& solver) {
  ScopedPhase timer(solver.phase_times(), Phase::Output);
  finish_pending();  // one frame at a time: its memory, and the order of the .pvd entries
  const std::size_t index = progress_.frame_times.size();
  const double time = solver.time();
  const std::string name = frame_name(index, comm_.distributed());
  // The copy of the arrays is the only part that reads the particles: the solver may go on once
  // it is made. The writer's thread owns the frame; pvd_ is touched only by one thread at a time
  // (the run loop's waits for the writer before it reads or writes pvd_ again).
  auto frame = std::make_shared<const ParticleFrame>(solver.particles(), time, body_names(solver.scene()));
  const bool distributed = comm_.distributed();
  const std::string path = (dir_ / (distributed ? frame_piece_name(index, comm_.rank()) : name)).string();
  writer_.start([this, frame, path, time, name, distributed] {
    const auto start = std::chrono::steady_clock::now();
    frame->write(path, compress_);
    if (!distributed) pvd_.add(time, name);  // a distributed run's summary waits for every piece
    if (background_) background_seconds_ += std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  });
  if (distributed) pending_summary_ = PendingSummary{index, time, &solver.particles()};
  progress_.frame_times.push_back(time);
  progress_.frame_steps.push_back(solver.step_count());
  if (!background_) finish_pending();
  return name;
}

void FrameSeries::complete(Solver& solver) {
  ScopedPhase timer(solver.phase_times(), Phase::Output);
  finish_pending();
}

void FrameSeries::list_finished_frame(Solver& solver) {
  if (!pending_summary_) return;  // (the same on every rank: frames are written at the same steps)
  if (comm_.any(!writer_.idle())) return;
  ScopedPhase timer(solver.phase_times(), Phase::Output);
  finish_pending();
}

void FrameSeries::finish_pending() {
  std::optional<PendingSummary> summary = std::exchange(pending_summary_, std::nullopt);
  if (!summary) {
    writer_.wait();
    return;
  }
  // A distributed run's pieces: a piece that could not be written (a full disk, a quota) is said
  // once, by rank 0, naming the rank, and every rank stops together. Each rank said it on its own
  // line before, once per rank, and MPI_Abort cut the job. The agreement is also the barrier: every
  // piece is on disk before the summary names it.
  comm_.agree([&] { writer_.wait(); });
  const std::string name = frame_name(summary->index, true);
  comm_.agree([&] {  // (rank 0 writes the summary and the .pvd)
    if (comm_.root()) {
      std::vector<std::string> pieces;  // relative to frames/, where the summary is
      for (int r = 0; r < comm_.size(); ++r)
        pieces.push_back(fs::path(frame_piece_name(summary->index, r)).filename().string());
      write_particles_pvtu((dir_ / name).string(), pieces, *summary->layout);
    }
    pvd_.add(summary->time, name);
  });
}

bool FrameSeries::has_frame_of_step(std::int64_t step) const {
  return !progress_.frame_steps.empty() && progress_.frame_steps.back() == step;
}

// ---- checkpoint.h5 ------------------------------------------------------------------------------

void CheckpointFile::write(Solver& solver, const RunProgress& progress) {
  ScopedPhase timer(solver.phase_times(), Phase::Output);
  // (rank 0 writes a distributed run's: its failure stops every rank together, said once)
  solver.comm().agree([&] { write_checkpoint(path_, solver, progress); });
}

}  // namespace talus
