#include "host_info.hpp"

#include "commands.hpp"
#include "talus/core/comm.hpp"

#include <fmt/core.h>
#include <omp.h>
#include <sched.h>
#include <unistd.h>

#include <algorithm>
#include <array>
#include <cstdint>
#include <cstdlib>
#include <cstring>
#include <fstream>
#include <functional>

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

int logical_cpus() { return std::max(1, static_cast<int>(::sysconf(_SC_NPROCESSORS_ONLN))); }

namespace {

// (libstdc++'s string hash has a fixed seed: every rank hashes a name alike)
std::uint64_t host_key() { return std::hash<std::string>{}(host_name()); }

/// The CPUs this process may run on, as a key: ranks with the same key on one host share them.
std::uint64_t cpu_set_key() {
  cpu_set_t set;
  CPU_ZERO(&set);
  if (::sched_getaffinity(0, sizeof set, &set) != 0) return 0;
  return std::hash<std::string>{}(std::string(reinterpret_cast<const char*>(&set), sizeof set));
}

}  // namespace

int set_rank_threads(int threads, const Comm& world) {
  world.agree([&] { set_threads(threads); });  // (an OMP_NUM_THREADS refused on one rank stops them all)
  if (!world.distributed()) return omp_get_max_threads();
  // (every rank gathers, whatever its own options and environment say: a collective)
  struct Place {
    std::uint64_t host, cpus;
  };
  const Place mine{host_key(), cpu_set_key()};
  const std::vector<Place> places = world.allgather(mine);
  const bool chosen = threads > 0 || std::getenv("OMP_NUM_THREADS") != nullptr;
  if (!chosen) {
    const auto sharing = std::count_if(places.begin(), places.end(),
                                       [&](const Place& p) { return p.host == mine.host && p.cpus == mine.cpus; });
    omp_set_num_threads(std::max(1, cpus_allowed() / static_cast<int>(std::max<std::ptrdiff_t>(1, sharing))));
  }
  return omp_get_max_threads();
}

namespace {

/// oversubscription_warning under mpirun: the threads of each host's ranks against its logical CPUs.
std::optional<std::string> host_oversubscription(const Comm& world, int threads) {
  struct Load {
    std::uint64_t host;
    int threads, cpus;
  };
  if (!world.distributed()) return std::nullopt;  // (one process: the bench's note judges it)
  const std::vector<Load> loads = world.allgather(Load{host_key(), threads, logical_cpus()});
  if (!world.root()) return std::nullopt;
  for (std::size_t r = 0; r < loads.size(); ++r) {
    bool first_of_host = true;
    for (std::size_t q = 0; q < r; ++q) first_of_host = first_of_host && loads[q].host != loads[r].host;
    if (!first_of_host) continue;
    int ranks = 0, sum = 0, least = loads[r].threads, most = loads[r].threads;
    for (const Load& l : loads)
      if (l.host == loads[r].host) {
        ++ranks;
        sum += l.threads;
        least = std::min(least, l.threads);
        most = std::max(most, l.threads);
      }
    if (sum <= loads[r].cpus) continue;
    const std::string each = least == most ? fmt::format("{}", most) : fmt::format("{}-{}", least, most);
    const std::string where = r == 0 ? fmt::format("host {}", host_name()) : fmt::format("the host of rank {}", r);
    const int fit = std::max(1, loads[r].cpus / ranks);
    return fmt::format("{} rank{} x {} thread{} = {} threads on {}, which has {} logical CPU{}: oversubscribed, "
                       "each thread waits for a CPU and the run is slower, not faster; give --threads {}{}",
                       ranks, ranks == 1 ? "" : "s", each, most == 1 ? "" : "s", sum, where, loads[r].cpus,
                       loads[r].cpus == 1 ? "" : "s", fit, ranks > loads[r].cpus ? " and fewer ranks on that host" : "");
  }
  return std::nullopt;
}

}  // namespace

std::optional<std::string> oversubscription_warning(const Comm& world, int threads_option, int threads) {
  if (world.distributed()) return host_oversubscription(world, threads);
  const auto over = oversubscription(threads);
  if (!over) return std::nullopt;
  const int cpus = cpus_allowed();
  const std::string given = threads_option > 0 ? fmt::format("--threads {}", threads_option)
                                               : fmt::format("OMP_NUM_THREADS={}", threads);
  return fmt::format("{}: {}: the threads take turns on the CPUs and wait for each other at every barrier, so the "
                     "run is slower than on {} threads; give --threads {} or fewer",
                     given, *over, cpus, cpus);
}

nlohmann::ordered_json host_json() {
  return {{"name", host_name()},
          {"cpu", cpu_model()},
          {"logical_cpus", logical_cpus()},
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
