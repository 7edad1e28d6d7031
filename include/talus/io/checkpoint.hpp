#pragma once
// Checkpoint/restart (docs/reliability.md): the full state of a run in one HDF5 file, written to a
// temporary name and renamed, so a reader only ever sees a complete checkpoint.
//
// Layout of checkpoint.h5:
//   /                      attributes format = "talus-checkpoint", format_version, talus_version,
//                          scene_hash (FNV-1a 64 of the resolved scene JSON, hex), scene_name
//   /scene_json            the resolved scene (scene_to_json), as bytes
//   /solver                attributes time, step, last_dt, the accumulated terms of the energy
//                          ledger by name (friction_work, plastic_work, outflow, damping;
//                          solver/energy_budget.hpp), outflow_mass, outflow_mass_x_plus, outflow_particles,
//                          steps_since_sort, sorts, needs_sort
//   /solver/sort_cell0..2  int32 per particle: the cell each particle was sorted into
//   /particles/<name>      one dataset per allocated particle array, named by
//                          ParticleStore::for_each_double_array / for_each_integer_array
//                          (x0.., v0.., mass, volume, volume0, stress0..5, strain0..5, ..., id, body)
//   /solver/ranks/*        distributed runs only: per rank, in rank order, the particle count
//                          (`particles`; the particle datasets hold rank 0's particles, then rank
//                          1's, ...), the rank's counters and accumulated ledger terms; and
//                          `slab_first_columns`, the slab bounds (docs/architecture.md)
//   /run                   attributes next_frame, next_history, next_checkpoint, the initial energy
//                          budget (initial_<term> for every ledger term), energy_max_released; datasets
//                          frame_times, frame_steps (the frames written so far); attributes
//                          runout_first_row, frame_folders (JSON [[first frame, folder], ...])
// The solver uses no random numbers, so there is no RNG state to save.
#include "talus/particles/particle_store.hpp"
#include "talus/scene/scene.hpp"
#include "talus/solver/solver.hpp"
#include "talus/solver/stability_guards.hpp"

#include <cstdint>
#include <map>
#include <optional>
#include <string>
#include <utility>
#include <vector>

namespace talus {

/// What the run driver needs to continue its output schedule.
struct RunProgress {
  std::vector<double> frame_times;         // frame i is frame_name(i): .vtu, or .pvtu when distributed
  std::vector<std::int64_t> frame_steps;
  double next_frame = 0.0;
  double next_history = 0.0;
  double next_checkpoint = 0.0;
  EnergyBudget initial;                    // the energy budget at t = 0
  double energy_max_released = 0.0;        // EnergyGuard state
  /// runout.csv's first row (io/runout_output.hpp runout_csv_row), the initial front: the gate
  /// when the scene sets none. Kept here because a folder may lack the rows of the run's start (a
  /// resume of a resume into another folder). Empty when the scene has no runout diagnostics.
  std::string runout_first_row;
  /// Where the frames were written: (first frame index, folder relative to the checkpoint's own
  /// folder), in frame order (relative, so that a run folder moved as a whole still finds them). A run
  /// resumed into another folder (--restart with --out) writes its frames there while the earlier
  /// ones stay where they were, so a later restart in that folder finds only its own. Empty in
  /// checkpoints written before it was kept (every frame then counts as the checkpoint folder's).
  std::vector<std::pair<std::size_t, std::string>> frame_folders;
  /// The run's energy warning so far (a resumed run neither warns again nor records a later step as
  /// the first); absent in checkpoints written before 2026-12-07.
  std::optional<EnergyWarning> energy_warning;
};

struct Checkpoint {
  std::string talus_version;
  std::string scene_hash;
  std::string scene_name;
  std::string scene_json;
  SolverState solver;
  std::map<std::string, std::vector<double>> double_arrays;
  std::vector<std::int64_t> id;
  std::vector<std::uint16_t> body;
  RunProgress run;
  /// Written by a distributed run (empty for one rank): each rank's particle count (its particles
  /// are stored one rank after the other), the slab bounds, and each rank's own counters and
  /// accumulated ledger (the /solver attributes hold their sums), so that a restart on the same
  /// number of ranks continues bit for bit.
  std::vector<std::int64_t> rank_particles;
  std::vector<std::int32_t> slab_first_columns;
  std::vector<SolverState> rank_states;  // the scalars only (no sort_cell)
  /// The particle arrays and sort cells hold only the reading rank's saved particles (read on the
  /// saved number of ranks, read_checkpoint with that Comm); otherwise every particle.
  bool own_part = false;
};

/// FNV-1a 64 of scene_to_json(scene).dump(), as 16 hex digits.
std::string scene_hash(const Scene& scene);

/// The keys a restart may change: time.end, time.courant, time.max_steps and guards.*. They steer
/// how the run goes on (how far, in what steps, what stops it), not the state it goes on from: an
/// instability's last good state resumed with a smaller time.courant, a finished run extended. What
/// the scene changes of them, one line each ("time.courant: 0.3 in the checkpoint's scene, 0.15
/// here"); empty when nothing. Any other difference is refused by restore_checkpoint.
std::vector<std::string> restart_changes(const Checkpoint& checkpoint, const Scene& scene);

/// Write the solver's state and the run progress to `path` (through path + ".tmp" and a rename).
/// Collective in a distributed run: the particles are gathered and rank 0 writes one file.
void write_checkpoint(const std::string& path, const Solver& solver, const RunProgress& run);

/// Read a checkpoint; throws an input Error naming the file if it is missing or unreadable. A rank
/// of `comm` that restarts a checkpoint of as many ranks reads only its own saved particles (each
/// read the whole file: a restart of 20 M particles on 16 ranks of a node took 120 GB for a while).
Checkpoint read_checkpoint(const std::string& path, const Comm& comm = Comm());

/// The number of ranks that wrote the checkpoint (1 for one rank), or 0 when the file cannot be
/// read as one (read_checkpoint then says why): what a restart's memory check needs to know first.
int checkpoint_ranks(const std::string& path);

/// The time and step a checkpoint holds (its /solver attributes, read alone: no particle is read),
/// or nothing when the file cannot be read as one.
std::optional<std::pair<double, std::int64_t>> checkpoint_time_and_step(const std::string& path);

/// Refuse a checkpoint of another talus version or another scene (input Error, one line, naming
/// the first key that differs), then put its state into `solver` (built from the same scene).
/// Any rank count can restart any checkpoint: on the saved number of ranks each rank takes its
/// saved particles and the run continues bit for bit; on another number the particles are dealt to
/// new balanced slabs and sorted anew (the run continues to round-off). Collective.
void restore_checkpoint(Solver& solver, const Checkpoint& checkpoint, const std::string& path);

}  // namespace talus
