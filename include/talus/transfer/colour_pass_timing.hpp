#pragma once
// Optional timing of the colour passes, block by block, for the work recorder
// (solver/work_recorder.hpp). The kernels take a pointer to it; null (the normal path) costs one
// predictable branch per block and per pass.
#include <array>
#include <vector>

namespace talus {

struct ColourPassTiming {
  /// Per colour: the seconds each block of sort.colour(c) took, in the order the loop hands them out.
  std::array<std::vector<double>, 8> block_seconds;
  /// Per colour: the wall time of the whole parallel loop (its fork, its blocks and its barrier).
  std::array<double, 8> wall{};
};

}  // namespace talus
