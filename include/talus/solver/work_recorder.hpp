#pragma once
// The work-distribution recorder: what each parallel region of a step did, for the scaling model
// (tools/scaling_model.py, docs/performance.md "Scaling"). For each recorded step it keeps, in the
// order the step runs them, every parallel region with its OpenMP schedule and the time it took:
//   colour passes and the stress pass (schedule(dynamic, 1) over blocks): the seconds and the
//     particles of every block, in the order the loop hands them out;
//   loops over particles or grid tiles (schedule(static)): their length and their time;
//   serial parts: their time.
// What the step took besides the regions it lists is serial glue (the model keeps it serial).
// With no recorder attached (Solver::record_work(nullptr), the normal path) nothing is timed.
#include "talus/particles/cell_sort.hpp"
#include "talus/transfer/colour_pass_timing.hpp"

#include <nlohmann/json_fwd.hpp>

#include <cstdint>
#include <iosfwd>
#include <string>
#include <vector>

namespace talus {

enum class RegionSchedule { Static, Dynamic, Serial };

struct WorkRegion {
  std::string name;
  RegionSchedule schedule = RegionSchedule::Serial;
  int chunk = 1;               // dynamic: the chunk size of the schedule
  int parallel_regions = 0;    // fork/join + barrier pairs inside (0 for serial parts)
  int barriers = 0;            // barriers without a fork/join: inside a parallel region opened before
                               // (the fused colour passes), or between the loops of a static region
  double seconds = 0.0;        // wall time of the region
  std::size_t items = 0;       // static: iterations of the loop (particles or tiles)
  std::vector<double> block_seconds;           // dynamic: per block, in hand-out order
  std::vector<std::uint32_t> block_particles;  // dynamic: particles per block, same order
};

struct WorkStep {
  std::int64_t step = 0;
  double seconds = 0.0;  // wall time of the whole step
  /// Of it, the recorder's own bookkeeping (the add_* calls): no part of an unrecorded step, so
  /// the model leaves it out of the step's serial glue.
  double recorder_seconds = 0.0;
  std::size_t particles = 0;
  std::size_t blocks = 0;
  std::vector<WorkRegion> regions;
};

/// Which steps a recorder keeps once it holds `max_steps` of them.
enum class RecordSpan {
  FirstSteps,  // stop recording (talus bench: the steps after the untimed one)
  WholeRun,    // thin out (talus run): keep every third recorded step and triple the interval, so
               // that the record keeps sampling the whole run evenly, however long it is
};

class WorkRecorder {
 public:
  /// Record every `interval`-th step that is offered (begin_step), at most `max_steps` of them;
  /// `span` says what happens when that many are held. A RecordSpan::WholeRun record is full as well
  /// once it holds kMaxRunBlockEntries block entries, so its memory does not grow with the scene.
  explicit WorkRecorder(int max_steps, int interval = 1, RecordSpan span = RecordSpan::FirstSteps)
      : max_steps_(max_steps), interval_(interval < 1 ? 1 : interval), span_(span) {}

  /// The block entries (one block's seconds and particles in one loop, 12 B, and about 40 B more
  /// while the record is written as JSON) past which a run's record takes no more steps: it holds at
  /// most this plus one step's entries, about 200 MB at its end. 1000 steps of the default flume hold
  /// 1.4 M; a run of 1 M particles reaches the bound at about 250 recorded steps and then keeps 80–250,
  /// every third one after each thinning. (A scene of some 50 M particles, whose one step passes the
  /// bound, keeps its first recorded step only.)
  static constexpr std::size_t kMaxRunBlockEntries = std::size_t(1) << 22;

  /// Called by the solver at the start of each step; true when this step is recorded.
  bool begin_step(std::int64_t step, std::size_t particles, std::size_t blocks);
  void end_step(double seconds);
  bool active() const { return active_; }
  /// Whether the last step offered was recorded (it stays true after end_step, until the next
  /// begin_step): the run loop adds its own time after such a step to it.
  bool last_step_recorded() const { return last_recorded_; }
  bool full() const {
    return static_cast<int>(steps_.size()) >= max_steps_ ||
           (span_ == RecordSpan::WholeRun && block_entries_ >= kMaxRunBlockEntries);
  }
  /// Block entries held (see kMaxRunBlockEntries).
  std::size_t block_entries() const { return block_entries_; }
  /// Steps between two recorded ones now (tripled at each thinning of a RecordSpan::WholeRun record).
  int interval() const { return interval_; }

  /// A static region: `items` iterations in `parallel_regions` parallel regions, with `barriers`
  /// barriers between loops inside them (TileStages: one region, a barrier between its loops).
  void add_static(const char* name, std::size_t items, int parallel_regions, double seconds, int barriers = 0);
  void add_serial(const char* name, double seconds);
  /// One region per colour of `timing` (8, or 1 for a single pass over all blocks).
  void add_colour_passes(const char* name, const ColourPassTiming& timing, const CellSort& sort, bool single_pass);
  /// A schedule(dynamic, 1) loop over all blocks in sort.blocks_in_work_order().
  void add_block_loop(const char* name, const std::vector<double>& block_seconds, double seconds, const CellSort& sort);
  /// The same for a loop over other work units (schedule(dynamic, 1) in the order given): each
  /// unit's seconds and particles (the MLS smoother's columns of cells).
  void add_unit_loop(const char* name, const std::vector<double>& unit_seconds, std::vector<std::uint32_t> unit_particles,
                     double seconds);
  /// Time the caller (the run loop) spent after the last recorded step: serial (output, guards), or
  /// with items > 0 a static region of that many iterations in `parallel_regions` regions (the snapshot).
  void add_after_step(const char* name, double seconds, std::size_t items = 0, int parallel_regions = 0);
  /// A whole run's times, for the model's run prediction. The run loop's output is spiky (a frame
  /// every few hundred steps), so the model takes its run mean rather than the sampled steps' share.
  struct RunTotals {
    std::int64_t steps = 0;
    double solver_seconds = 0.0;
    double other_seconds = 0.0;  // outside the steps; of it, the parallel parts below
    double snapshot_seconds = 0.0;  // the field checks before and the copies of the snapshots
    std::int64_t snapshot_regions = 0;
    double history_seconds = 0.0;  // the history rows: energies, runout (parallel loops and sort), files
    std::int64_t history_regions = 0;  // as on many threads (the sort's merge levels)
    // the frames' writes on the writer's thread (FrameSeries), beside the steps and not part of any of
    // the times above; the model shares them among the cores
    double background_seconds = 0.0;
  };
  void set_totals(const RunTotals& totals) { totals_ = totals; }

  const std::vector<WorkStep>& steps() const { return steps_; }
  /// Wall time of an empty `omp parallel for` (fork, a loop of `threads` iterations, barrier) at
  /// each thread count 1..max_threads: the per-region cost the model adds (best of 5 x 2000).
  static std::vector<double> measure_fork_join(int max_threads);
  /// Wall time of an empty `omp for schedule(dynamic, 1)` of `threads` iterations inside a parallel
  /// region already open (a barrier and the loop's hand-out, no fork): per thread count, as above.
  static std::vector<double> measure_barrier(int max_threads);
  /// The threading facts a record's model needs, for 1 .. max(OpenMP threads, processors):
  /// fork_join_seconds and barrier_seconds (above), and the OpenMP settings they depend on
  /// (omp_wait_policy, omp_proc_bind, omp_places: the environment's values, "unset" where unset).
  /// The wait policy matters most: with OMP_WAIT_POLICY=PASSIVE every region wakes sleeping
  /// threads (11–15 µs at 2 threads, 38–218 µs at 16, measured on a 16-core VM).
  static nlohmann::json threading_meta();
  /// An OpenMP setting as the environment gives it (e.g. "OMP_WAIT_POLICY"), "unset" where unset.
  static std::string openmp_setting(const char* name);
  /// OMP_WAIT_POLICY, OMP_PROC_BIND and OMP_PLACES as set ("unset" where not), under lower-case keys
  /// (omp_wait_policy, ...): the record's, the bench's and run.json's.
  static nlohmann::json openmp_settings();
  /// OMP_WAIT_POLICY=PASSIVE (any case): the threads sleep as soon as a region ends.
  static bool passive_wait_policy();

  /// Write the record to `out` as one line of JSON ("format": "talus-work-record/1", `meta` merged in,
  /// "steps" last), a step at a time: no tree of the whole record, nor a string of it, is held.
  void write_json(std::ostream& out, const nlohmann::json& meta) const;

 private:
  int max_steps_, interval_;
  RecordSpan span_;
  std::int64_t offered_ = 0;
  bool active_ = false, last_recorded_ = false;
  std::vector<WorkStep> steps_;
  std::size_t block_entries_ = 0;
  RunTotals totals_;
};

}  // namespace talus
