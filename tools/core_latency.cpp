// How long a cache line takes to travel from one core to another: two threads, pinned to CPU 0 and
// to CPU c, hand one cache line back and forth. It prints the one-way time in ns for each CPU given.
//
//   g++ -O2 -pthread tools/core_latency.cpp -o /tmp/core_latency && /tmp/core_latency 1 7 15
//
// Why: a small scene (the default flume) lives in the caches, and with a dynamic schedule its blocks,
// nodes and barriers pass between the cores' caches in every pass. Its per-core slowdown c(T)
// follows this time. On the 2-vCPU development VM, the 2-thread flume ran at 10.0–10.3 M/s while this
// printed 205–234 ns, and at 13.5–14.1 M/s (×1.84) while it printed 56–60 ns, the same day and binary
// (docs/performance.md, "2 threads when the host puts the vCPUs far apart"). tools/node_scaling.sh records it.
#include <pthread.h>
#include <sched.h>

#include <algorithm>
#include <atomic>
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <thread>

namespace {

alignas(64) std::atomic<long> token{0};

bool pin(int cpu) {
  cpu_set_t set;
  CPU_ZERO(&set);
  CPU_SET(cpu, &set);
  return pthread_setaffinity_np(pthread_self(), sizeof set, &set) == 0;
}

// The CPUs this process may run on, read before main pins itself to CPU 0. A CPU outside them is
// refused: two spinning threads on one CPU would take a time slice for every trip.
cpu_set_t allowed_cpus;
bool allowed(int cpu) { return cpu >= 0 && cpu < CPU_SETSIZE && CPU_ISSET(cpu, &allowed_cpus); }

// The thread on `cpu` answers odd values, the caller (on CPU 0) even ones: 2 * rounds one-way trips.
double one_way_ns(int cpu, long rounds) {
  token = 0;
  std::thread other([&] {
    pin(cpu);
    for (long i = 1; i < 2 * rounds; i += 2) {
      while (token.load(std::memory_order_acquire) != i) {
      }
      token.store(i + 1, std::memory_order_release);
    }
  });
  const auto start = std::chrono::steady_clock::now();
  for (long i = 0; i < 2 * rounds; i += 2) {
    while (token.load(std::memory_order_acquire) != i) {
    }
    token.store(i + 1, std::memory_order_release);
  }
  while (token.load(std::memory_order_acquire) != 2 * rounds) {
  }
  const auto end = std::chrono::steady_clock::now();
  other.join();
  return std::chrono::duration<double, std::nano>(end - start).count() / (2.0 * static_cast<double>(rounds));
}

}  // namespace

int main(int argc, char** argv) {
  if (argc < 2) {
    std::fprintf(stderr, "usage: core_latency CPU [CPU ...]  (one-way cache-line time from CPU 0 to each)\n");
    return 2;
  }
  CPU_ZERO(&allowed_cpus);
  if (sched_getaffinity(0, sizeof allowed_cpus, &allowed_cpus) != 0 || !CPU_ISSET(0, &allowed_cpus) || !pin(0)) {
    std::fprintf(stderr, "core_latency: cannot pin to CPU 0\n");
    return 1;
  }
  for (int a = 1; a < argc; ++a) {
    const int cpu = std::atoi(argv[a]);
    if (cpu == 0 || !allowed(cpu)) {
      std::printf("CPU 0 -> %s: not a CPU this process may use besides 0\n", argv[a]);
      continue;
    }
    double best = 1e30;
    for (int repeat = 0; repeat < 3; ++repeat) best = std::min(best, one_way_ns(cpu, 500000));
    std::printf("CPU 0 -> %d: %.1f ns one way (best of 3)\n", cpu, best);
  }
  return 0;
}
