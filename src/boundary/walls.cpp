#include "talus/boundary/walls.hpp"

namespace talus {

Walls::Walls(const std::array<std::array<WallSpec, 2>, 3>& specs, const GridGeometry& geometry) : specs_(specs) {
  for (int d = 0; d < 3; ++d) {
    lower_[d] = kPad;
    upper_[d] = kPad + geometry.cells[d];
    for (int side = 0; side < 2; ++side) active_[d][side] = specs[d][side].type != WallType::Open;
  }
}

}  // namespace talus
