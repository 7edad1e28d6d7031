#pragma once
// What the machine a command runs on says of itself: its name, its CPU, and this process's memory.
// The bench's JSON and a run's record (run.json) carry them, so that a figure names its machine.
#include <cstddef>
#include <string>

namespace talus::app {

/// The CPU's model name from /proc/cpuinfo ("unknown" where there is none).
std::string cpu_model();
/// The host's name ("unknown" where it cannot be read).
std::string host_name();
/// A memory line of /proc/self/status in bytes: "VmHWM:" (peak resident) or "VmRSS:" (now); 0 where
/// there is no such line.
std::size_t status_bytes(const char* key);
/// This process's peak resident memory so far [B] (VmHWM).
inline std::size_t peak_rss_bytes() { return status_bytes("VmHWM:"); }

}  // namespace talus::app
