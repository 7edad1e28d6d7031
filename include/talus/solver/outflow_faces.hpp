#pragma once
// What left through each face of the grid (Solver::remove_outflow): mass and particle count per
// face, for run.json's end.outflow_by_face. The runout diagnostics had only the share through x+
// (ahead of the front); a slide that lost mass through a side or the floor could not tell where.
#include "talus/transfer/transfers.hpp"

#include <array>
#include <cstdint>

namespace talus {

struct OutflowFaces {
  /// Face index 2 d + side, d the axis (x, y, z) and side 0 for the low face.
  static constexpr int kFaces = 6;
  static constexpr int kXPlus = 1;
  static constexpr std::array<const char*, kFaces> kNames = {"x-", "x+", "y-", "y+", "z-", "z+"};

  std::array<double, kFaces> mass{};               // [kg]
  std::array<std::int64_t, kFaces> particles{};

  void add(int face, double particle_mass) {
    mass[face] += particle_mass;
    ++particles[face];
  }
};

/// The open face a particle at `point` (x, y, w: GatherOptions' frame) leaves through, -1 when it
/// lies beyond none. One beyond two open faces at once (past a corner) counts at one of them: x+
/// first, as the share ahead of the runout's front always counted it, then x-, y-, y+, z-, z+.
inline int outflow_face(const GatherOptions& limits, const double point[3]) {
  if (limits.open[0][1] && point[0] > limits.hi[0]) return OutflowFaces::kXPlus;
  for (int d = 0; d < 3; ++d) {
    if (limits.open[d][0] && point[d] < limits.lo[d]) return 2 * d;
    if (limits.open[d][1] && point[d] > limits.hi[d]) return 2 * d + 1;
  }
  return -1;
}

}  // namespace talus
