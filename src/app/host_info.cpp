#include "host_info.hpp"

#include <fmt/core.h>

#include <omp.h>
#include <unistd.h>

#include <array>
#include <fstream>

namespace talus::app {

std::string cpu_model() {
  std::ifstream info("/proc/cpuinfo");
  for (std::string line; std::getline(info, line);)
    if (line.rfind("model name", 0) == 0) return line.substr(line.find(':') + 2);
  return "unknown";
}

std::string host_name() {
  std::array<char, 256> name{};
  if (::gethostname(name.data(), name.size() - 1) != 0 || name[0] == '\0') return "unknown";
  return name.data();
}

int cpus_allowed() { return omp_get_num_procs(); }

std::optional<std::string> oversubscription(int threads) {
  const int cpus = cpus_allowed();
  if (threads <= cpus) return std::nullopt;
  return fmt::format("{} threads on the {} CPU{} this process may use: oversubscribed", threads, cpus, cpus == 1 ? "" : "s");
}

nlohmann::ordered_json host_json() {
  return {{"name", host_name()},
          {"cpu", cpu_model()},
          {"logical_cpus", ::sysconf(_SC_NPROCESSORS_ONLN)},
          {"cpus_allowed", cpus_allowed()}};
}

std::string utc_text(std::time_t time) {
  std::tm utc{};
  gmtime_r(&time, &utc);
  char text[32];
  std::strftime(text, sizeof text, "%Y-%m-%dT%H:%M:%SZ", &utc);
  return text;
}

std::size_t status_bytes(const char* key) {
  std::ifstream status("/proc/self/status");
  const std::string prefix = key;
  for (std::string line; std::getline(status, line);)
    if (line.rfind(prefix, 0) == 0) return std::stoull(line.substr(prefix.size())) * 1024;
  return 0;
}

}  // namespace talus::app
