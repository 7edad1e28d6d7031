#pragma once
// What a scene will need in memory, known before anything is allocated: `talus check` prints it and
// `talus run` refuses a scene that does not fit, with one line (needed, available, what to change)
// and exit code 2, instead of running until an allocation fails (docs/reliability.md "Memory").
//
// The model counts the arrays the solver really holds, per particle (fields, sort and scratch
// arrays, MLS buffers, the guard's snapshot copy, the largest transient buffer: a VTU frame) and
// per grid node (12 doubles, committed tile by tile where particles are). The grid part is the
// tiles the bodies cover at the start; a flow that spreads commits more, at most the whole grid
// (reported as `grid_bytes_bound`). tests/solver/memory_estimate_test.cpp checks the model against
// the peak resident memory of real runs.
#include "talus/scene/scene.hpp"

#include <cstddef>
#include <optional>
#include <string>

namespace talus {

struct MemoryEstimate {
  std::size_t particles = 0;           // exact: the particles seeding will make
  std::size_t bytes_per_particle = 0;  // every per-particle array the run holds at its peak
  std::size_t particle_bytes = 0;      // particles * bytes_per_particle
  std::size_t grid_bytes = 0;          // node data of the tiles the bodies cover at the start, and the ghost map
  std::size_t grid_bytes_bound = 0;    // node data of the whole grid (a flow that covers it all), and the ghost map
  std::size_t total() const { return particle_bytes + grid_bytes; }
};

/// What the estimate counts: a run (the solver, a frame's arrays while it is written, the guard's
/// snapshot of the last good state) or the solver alone (what `talus bench` holds).
enum class MemoryScope { Run, Solver };

/// Counts the particles (particles/seeding.hpp count_particles: same input errors, no allocation)
/// and sizes what the solver and, for a run, the run's outputs will hold.
MemoryEstimate estimate_memory(const Scene& scene, MemoryScope scope = MemoryScope::Run);

/// The bytes a checkpoint holds for each particle (its fields, their sort cells, the `reused` MLS
/// variant's weights): about checkpoint.h5's size per particle, what a restart reads of it.
std::size_t checkpoint_bytes_per_particle(const Scene& scene);

/// Memory this process may still use [bytes]: the environment variable TALUS_MEMORY_LIMIT when set
/// (bytes, or with a K/M/G/T suffix: a share of a node for one run), else the smaller of the
/// system's MemAvailable and the room left under a cgroup (container, batch job) limit. Throws
/// input_error for a TALUS_MEMORY_LIMIT that is not a positive size. nullopt when unknown.
std::optional<std::size_t> available_memory();

/// How a run's processes sit on the machines: one process (the default), or under mpirun `ranks`
/// ranks, `ranks_here` of them on this machine.
struct MachineShare {
  int ranks = 1;
  int ranks_here = 1;
  bool root_here = true;  // rank 0 runs here
  bool restart = false;   // the run starts from a checkpoint
  bool restart_reads_own_part = false;  // of as many ranks: each rank reads only its own particles
};

/// What this machine holds at the run's peak: its ranks' share of the estimate (the slabs split the
/// particles and the grid about evenly); in a distributed run, on rank 0's machine, the fields of
/// every particle, which rank 0 gathers for checkpoints and runout rows; and on a distributed
/// restart, the checkpoint's particles and a copy of them that each rank here holds while it takes
/// its own (io/checkpoint.hpp restore_checkpoint): its own part on the saved number of ranks, else
/// the whole.
std::size_t bytes_on_this_machine(const Scene& scene, const MemoryEstimate& estimate, const MachineShare& share);

/// Throws input_error (exit code 2) when what this machine holds (bytes_on_this_machine) exceeds the
/// available memory, with the figures and what to change. Does nothing when the available memory is unknown.
void require_memory_fits(const Scene& scene, const MemoryEstimate& estimate, const MachineShare& share = {});

/// The warning when the start fits but a flow that covers the whole grid (grid_bytes_bound) would
/// not: `talus check` printed a plain "ok" beside "up to 79.74 GB ...; 19.98 GB available". Nothing
/// when it fits, or the available memory is unknown. One process only (a distributed run splits
/// the grid among its ranks).
std::optional<std::string> memory_bound_warning(const MemoryEstimate& estimate, const MachineShare& share = {});

/// Bytes as "1.23 GB" (powers of 1000, as `talus check` prints them).
std::string format_bytes(double bytes);

}  // namespace talus
