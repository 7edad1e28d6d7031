#pragma once
// Wall-clock seconds spent in each phase of the step, accumulated over a run (for `talus bench`
// and the end-of-run summary). Timing a phase costs two clock reads.
#include <array>
#include <chrono>
#include <ctime>

namespace talus {

// Smooth: the MLS fit of the strain increments (only when the scene enables it); Stress holds the
// strain pass and the material update around it. Grid and Remap hold the node work after their
// scatter (one parallel region since 2026-12-04): with block buffers the sum of the boxes, the
// ghost fold, the velocities and the mirror; P2G and G2P hold the scatters themselves.
enum class Phase { Sort, P2G, Grid, G2P, Remap, Smooth, Stress, Output, Count };
inline constexpr std::array<const char*, static_cast<int>(Phase::Count)> kPhaseNames = {
    "sort", "p2g", "grid", "g2p", "remap", "smooth", "stress", "output"};

struct PhaseTimes {
  std::array<double, static_cast<int>(Phase::Count)> seconds{};
  double& operator[](Phase p) { return seconds[static_cast<int>(p)]; }
  double operator[](Phase p) const { return seconds[static_cast<int>(p)]; }
  double total() const {
    double t = 0.0;
    for (double s : seconds) t += s;
    return t;
  }
};

/// Which clock times the phases: the wall clock (default), or the CPU time of the whole process
/// (`talus bench --cpu-time`): on a shared machine a one-thread bench is then not charged for the
/// time it waited for a core. With several threads CPU time adds up over the threads.
enum class PhaseClock { Wall, ProcessCpu };
inline PhaseClock& phase_clock() {
  static PhaseClock clock = PhaseClock::Wall;
  return clock;
}
/// Seconds on the phase clock (any origin; differences only).
inline double phase_clock_seconds() {
  if (phase_clock() == PhaseClock::ProcessCpu) {
    timespec t{};
    clock_gettime(CLOCK_PROCESS_CPUTIME_ID, &t);
    return double(t.tv_sec) + 1e-9 * double(t.tv_nsec);
  }
  return std::chrono::duration<double>(std::chrono::steady_clock::now().time_since_epoch()).count();
}

/// Adds the lifetime of the object to one phase.
class ScopedPhase {
 public:
  ScopedPhase(PhaseTimes& times, Phase phase) : times_(times), phase_(phase), start_(phase_clock_seconds()) {}
  ~ScopedPhase() { times_[phase_] += phase_clock_seconds() - start_; }
  ScopedPhase(const ScopedPhase&) = delete;
  ScopedPhase& operator=(const ScopedPhase&) = delete;

 private:
  PhaseTimes& times_;
  Phase phase_;
  double start_;
};

}  // namespace talus
