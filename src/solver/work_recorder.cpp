#include "talus/solver/work_recorder.hpp"

#include <nlohmann/json.hpp>
#include <omp.h>

#include <algorithm>
#include <cctype>
#include <cstdlib>
#include <ostream>
#include <string>

namespace talus {

namespace {

/// Adds the time from its construction to its end to `seconds`: the recorder's own cost.
class OwnTime {
 public:
  explicit OwnTime(double& seconds) : seconds_(seconds), start_(omp_get_wtime()) {}
  ~OwnTime() { seconds_ += omp_get_wtime() - start_; }
  OwnTime(const OwnTime&) = delete;
  OwnTime& operator=(const OwnTime&) = delete;

 private:
  double& seconds_;
  double start_;
};

}  // namespace

namespace {
constexpr int kThinning = 3;  // a full RecordSpan::WholeRun record keeps every kThinning-th step
}  // namespace

bool WorkRecorder::begin_step(std::int64_t step, std::size_t particles, std::size_t blocks) {
  const std::int64_t offered = offered_++;
  if (offered % interval_ == 0 && full() && span_ == RecordSpan::WholeRun) {
    // The recorded steps were offered at 0, i, 2i, ...: keep 0, 3i, 6i, ... and go on every 3i.
    // Three, not two: an interval coprime with the sort's cadence (every 20 steps) stays so. Doubling
    // 7 gave 56 within three thinnings, and then every 5th recorded step was a sort step, not every 20th.
    std::size_t kept = 0;
    for (std::size_t k = 0; k < steps_.size(); k += kThinning, ++kept)
      if (kept != k) steps_[kept] = std::move(steps_[k]);  // a vector moved onto itself would empty
    steps_.resize(kept);
    interval_ *= kThinning;
    block_entries_ = 0;
    for (const WorkStep& s : steps_)
      for (const WorkRegion& r : s.regions) block_entries_ += r.block_seconds.size();
  }
  active_ = !full() && offered % interval_ == 0;
  last_recorded_ = active_;
  if (active_) {
    steps_.emplace_back();
    steps_.back().step = step;
    steps_.back().particles = particles;
    steps_.back().blocks = blocks;
  }
  return active_;
}

void WorkRecorder::end_step(double seconds) {
  if (active_) steps_.back().seconds = seconds;
  active_ = false;
}

void WorkRecorder::add_static(const char* name, std::size_t items, int parallel_regions, double seconds, int barriers) {
  if (!active_) return;
  const OwnTime own(steps_.back().recorder_seconds);
  WorkRegion r;
  r.name = name;
  r.schedule = RegionSchedule::Static;
  r.items = items;
  r.parallel_regions = parallel_regions;
  r.barriers = barriers;
  r.seconds = seconds;
  steps_.back().regions.push_back(std::move(r));
}

void WorkRecorder::add_serial(const char* name, double seconds) {
  if (!active_) return;
  const OwnTime own(steps_.back().recorder_seconds);
  WorkRegion r;
  r.name = name;
  r.seconds = seconds;
  steps_.back().regions.push_back(std::move(r));
}

void WorkRecorder::add_colour_passes(const char* name, const ColourPassTiming& timing, const CellSort& sort,
                                     bool single_pass) {
  if (!active_) return;
  const OwnTime own(steps_.back().recorder_seconds);
  for (int c = 0; c < (single_pass ? 1 : 8); ++c) {
    WorkRegion r;
    r.name = single_pass ? std::string(name) : std::string(name) + " colour " + std::to_string(c);
    r.schedule = RegionSchedule::Dynamic;
    // the colours share one parallel region: a fork/join for the first, a barrier after each other
    r.parallel_regions = c == 0 ? 1 : 0;
    r.barriers = c == 0 ? 0 : 1;
    r.seconds = timing.wall[c];
    r.block_seconds = timing.block_seconds[c];
    const std::size_t count = r.block_seconds.size();
    r.block_particles.resize(count);
    for (std::size_t bi = 0; bi < count; ++bi) {
      const std::size_t b = single_pass ? sort.blocks_in_work_order()[bi] : sort.colour(c)[bi];
      r.block_particles[bi] = sort.block_end(b) - sort.block_begin(b);
    }
    block_entries_ += count;
    steps_.back().regions.push_back(std::move(r));
  }
}

void WorkRecorder::add_block_loop(const char* name, const std::vector<double>& block_seconds, double seconds,
                                  const CellSort& sort) {
  if (!active_) return;
  std::vector<std::uint32_t> particles(block_seconds.size());
  for (std::size_t bi = 0; bi < block_seconds.size(); ++bi) {
    const std::size_t b = sort.blocks_in_work_order()[bi];
    particles[bi] = sort.block_end(b) - sort.block_begin(b);
  }
  add_unit_loop(name, block_seconds, std::move(particles), seconds);
}

void WorkRecorder::add_unit_loop(const char* name, const std::vector<double>& unit_seconds,
                                 std::vector<std::uint32_t> unit_particles, double seconds) {
  if (!active_) return;
  const OwnTime own(steps_.back().recorder_seconds);
  WorkRegion r;
  r.name = name;
  r.schedule = RegionSchedule::Dynamic;
  r.parallel_regions = 1;
  r.seconds = seconds;
  r.block_seconds = unit_seconds;
  r.block_particles = std::move(unit_particles);
  block_entries_ += r.block_seconds.size();
  steps_.back().regions.push_back(std::move(r));
}

void WorkRecorder::add_after_step(const char* name, double seconds, std::size_t items, int parallel_regions) {
  if (steps_.empty()) return;
  WorkRegion r;
  r.name = name;
  r.seconds = seconds;
  if (items > 0) {
    r.schedule = RegionSchedule::Static;
    r.items = items;
    r.parallel_regions = parallel_regions;
  }
  steps_.back().regions.push_back(std::move(r));
  steps_.back().seconds += seconds;
}

namespace {

/// For T = 1 .. max_threads threads, the best of 5 trials of `seconds(T)` (the seconds one
/// operation took in a trial); index 0 is unused.
template <class Trial>
std::vector<double> best_per_thread_count(int max_threads, Trial seconds) {
  const int saved = omp_get_max_threads();
  std::vector<double> cost(static_cast<std::size_t>(max_threads) + 1, 0.0);
  for (int t = 1; t <= max_threads; ++t) {
    omp_set_num_threads(t);
    double best = 1e300;
    for (int trial = 0; trial < 5; ++trial) best = std::min(best, seconds(t));
    cost[t] = best;
  }
  omp_set_num_threads(saved);
  return cost;
}

constexpr int kRepeats = 2000;  // regions or loops timed together in one trial

}  // namespace

std::vector<double> WorkRecorder::measure_fork_join(int max_threads) {
  volatile int sink = 0;
  return best_per_thread_count(max_threads, [&](int t) {
    const double start = omp_get_wtime();
    for (int r = 0; r < kRepeats; ++r) {
#pragma omp parallel for schedule(dynamic, 1)
      for (int i = 0; i < t; ++i) sink = sink + i;  // as the colour passes: dynamic, one item per thread
    }
    return (omp_get_wtime() - start) / kRepeats;
  });
}

std::vector<double> WorkRecorder::measure_barrier(int max_threads) {
  volatile int sink = 0;
  return best_per_thread_count(max_threads, [&](int t) {
    double seconds = 0.0;
#pragma omp parallel
    {
      const double start = omp_get_wtime();
      for (int r = 0; r < kRepeats; ++r) {
#pragma omp for schedule(dynamic, 1)
        for (int i = 0; i < t; ++i) sink = sink + i;  // as the fused colour passes: one loop per colour
      }
#pragma omp master
      seconds = omp_get_wtime() - start;
    }
    return seconds / kRepeats;
  });
}

namespace {

nlohmann::json step_to_json(const WorkStep& s) {
  nlohmann::json js;
  js["step"] = s.step;
  js["seconds"] = s.seconds;
  js["recorder_seconds"] = s.recorder_seconds;
  js["particles"] = s.particles;
  js["blocks"] = s.blocks;
  nlohmann::json regions = nlohmann::json::array();
  for (const WorkRegion& r : s.regions) {
    nlohmann::json jr;
    jr["name"] = r.name;
    jr["schedule"] = r.schedule == RegionSchedule::Static ? "static" : r.schedule == RegionSchedule::Dynamic ? "dynamic" : "serial";
    if (r.schedule == RegionSchedule::Dynamic) {
      jr["chunk"] = r.chunk;
      jr["block_seconds"] = r.block_seconds;
      jr["block_particles"] = r.block_particles;
    }
    if (r.schedule == RegionSchedule::Static) jr["items"] = r.items;
    jr["parallel_regions"] = r.parallel_regions;
    if (r.barriers > 0) jr["barriers"] = r.barriers;
    jr["seconds"] = r.seconds;
    regions.push_back(std::move(jr));
  }
  js["regions"] = std::move(regions);
  return js;
}

}  // namespace

void WorkRecorder::write_json(std::ostream& out, const nlohmann::json& meta) const {
  nlohmann::json j = meta;
  j["format"] = "talus-work-record/1";
  j["record_interval"] = interval_;  // steps between the recorded ones (at the end of a thinned run record)
  if (totals_.steps > 0) {
    const RunTotals& t = totals_;
    j["run_steps"] = t.steps;
    j["run_solver_seconds"] = t.solver_seconds;
    j["run_other_seconds"] = t.other_seconds;  // includes the snapshots and the history rows
    j["run_snapshot_seconds"] = t.snapshot_seconds;  // field checks and copies of the snapshots (parallel)
    j["run_snapshot_regions"] = t.snapshot_regions;
    j["run_history_seconds"] = t.history_seconds;  // the history rows (mostly parallel)
    j["run_history_regions"] = t.history_regions;
    j["run_background_seconds"] = t.background_seconds;  // frames written on the writer's thread
  }
  // The small head as one object, its closing brace replaced by the steps, written one at a time.
  std::string head = j.dump();
  head.pop_back();
  out << head << (j.empty() ? "" : ",") << "\"steps\":[";
  for (std::size_t k = 0; k < steps_.size(); ++k) out << (k ? "," : "") << step_to_json(steps_[k]);
  out << "]}\n";
}

nlohmann::json WorkRecorder::threading_meta() {
  const int max_threads = std::max(omp_get_max_threads(), omp_get_num_procs());
  nlohmann::json meta;
  meta["fork_join_seconds"] = measure_fork_join(max_threads);  // index = thread count (0 unused)
  meta["barrier_seconds"] = measure_barrier(max_threads);
  meta.update(openmp_settings());
  return meta;
}

nlohmann::json WorkRecorder::openmp_settings() {
  nlohmann::json settings;
  for (const char* name : {"OMP_WAIT_POLICY", "OMP_PROC_BIND", "OMP_PLACES"}) {
    std::string key(name);
    std::transform(key.begin(), key.end(), key.begin(), [](unsigned char c) { return std::tolower(c); });
    settings[key] = openmp_setting(name);
  }
  return settings;
}

std::string WorkRecorder::openmp_setting(const char* name) {
  const char* value = std::getenv(name);
  return value ? value : "unset";
}

bool WorkRecorder::passive_wait_policy() {
  std::string value = openmp_setting("OMP_WAIT_POLICY");
  std::transform(value.begin(), value.end(), value.begin(), [](unsigned char c) { return std::toupper(c); });
  return value == "PASSIVE";
}

}  // namespace talus
