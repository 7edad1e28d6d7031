#pragma once
// Wall-clock seconds spent in each phase of the step, accumulated over a run (for `talus bench`
// and the end-of-run summary). Timing a phase costs two clock reads.
#include <array>
#include <chrono>

namespace talus {

// Smooth: the MLS fit of the strain increments (only when the scene enables it); Stress holds the
// strain pass and the material update around it.
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

/// Adds the lifetime of the object to one phase.
class ScopedPhase {
 public:
  ScopedPhase(PhaseTimes& times, Phase phase) : times_(times), phase_(phase), start_(std::chrono::steady_clock::now()) {}
  ~ScopedPhase() {
    times_[phase_] += std::chrono::duration<double>(std::chrono::steady_clock::now() - start_).count();
  }
  ScopedPhase(const ScopedPhase&) = delete;
  ScopedPhase& operator=(const ScopedPhase&) = delete;

 private:
  PhaseTimes& times_;
  Phase phase_;
  std::chrono::steady_clock::time_point start_;
};

}  // namespace talus
