#pragma once
// What the machine a command runs on says of itself: its name, its CPU, its clock, and this process's memory.
// The bench's JSON and a run's record (run.json) carry them, so that a figure names its machine.
#include <nlohmann/json.hpp>

#include <cstddef>
#include <ctime>
#include <optional>
#include <string>

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
