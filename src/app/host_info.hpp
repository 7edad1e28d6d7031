#pragma once
// What the machine a command runs on says of itself: its name, its CPU, its clock, and this process's memory.
// The bench's JSON and a run's record (run.json) carry them, so that a figure names its machine.
#include <nlohmann/json.hpp>

#include <cstddef>
#include <ctime>
#include <optional>
#include <string>

namespace talus {
class Comm;
}

namespace talus::app {

/// The CPU's model name from /proc/cpuinfo ("unknown" where there is none).
std::string cpu_model();
/// The host's name ("unknown" where it cannot be read).
std::string host_name();
/// The CPUs this process may run on: fewer than the host's under mpirun's binding or taskset.
int cpus_allowed();
/// More threads than this process has CPUs: "8 threads on the 2 CPUs this process may use:
/// oversubscribed" (the bench's note and the run's warning say it), or nothing.
std::optional<std::string> oversubscription(int threads);

/// The host's logical CPUs online.
int logical_cpus();

/// The threads of each rank of a command that runs kernels (run, check, bench; collective under
/// mpirun): `threads` when given (--threads), else OMP_NUM_THREADS, else the CPUs this process may use;
/// under mpirun, shared among the ranks on this host that may use the same CPUs, at least 1 (each
/// rank took them all, and 3 ranks on 2 CPUs ran far slower than on one thread each: docs/architecture.md,
/// "Distributed runs"). Sets
/// OpenMP's thread count (set_threads) and returns it.
int set_rank_threads(int threads, const Comm& world);
/// On rank 0, the warning (without "talus: warning: ") that `run`, `check` and `bench` give when the
/// threads would oversubscribe the CPUs: each thread then waits for a CPU and the run is slower, not
/// faster. One process: `threads` (set_rank_threads's) against the CPUs it may use, naming where the
/// count came from (`threads_option`, --threads, or OMP_NUM_THREADS: the latter was not warned about).
/// Under mpirun (collective): the threads of the ranks on each host (every rank's own) against its
/// logical CPUs. nullopt on the other ranks and when nothing is oversubscribed.
std::optional<std::string> oversubscription_warning(const Comm& world, int threads_option, int threads);

/// The host as a figure's record names it (run.json and the bench's JSON): name, CPU model, logical
/// CPUs online, and those this process may run on.
nlohmann::ordered_json host_json();
/// A time as UTC, ISO 8601 to the second ("2026-12-06T13:40:05Z"): when a record was made.
std::string utc_text(std::time_t time);
/// A memory line of /proc/self/status in bytes: "VmHWM:" (peak resident) or "VmRSS:" (now); 0 where
/// there is no such line.
std::size_t status_bytes(const char* key);
/// This process's peak resident memory so far [B] (VmHWM).
inline std::size_t peak_rss_bytes() { return status_bytes("VmHWM:"); }

}  // namespace talus::app
