#include "talus/boundary/walls.hpp"

namespace talus {

Walls::Walls(const std::array<std::array<WallSpec, 2>, 3>& specs, const GridGeometry& geometry,
             const ProfileTerrain& bed)
    : specs_(specs) {
  if (geometry.has_terrain())
    for (int i = 0; i < bed.columns(); ++i) bed_normal_.push_back(bed.node_normal(i));
  for (int d = 0; d < 3; ++d) {
    lower_[d] = kPad;
    upper_[d] = kPad + geometry.cells[d];
    for (int side = 0; side < 2; ++side) active_[d][side] = specs[d][side].type != WallType::Open && specs[d][side].type != WallType::Periodic;
  }
}

const char* to_string(WallType type) {
  switch (type) {
    case WallType::Open: return "open";
    case WallType::Slip: return "slip";
    case WallType::Fixed: return "fixed";
    case WallType::Friction: return "friction";
    case WallType::Periodic: return "periodic";
  }
  return "?";
}

const char* face_name(int axis, int side) {
  static const char* const names[3][2] = {{"x-", "x+"}, {"y-", "y+"}, {"z-", "z+"}};
  return names[axis][side];
}

}  // namespace talus
