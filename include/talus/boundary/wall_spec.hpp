#pragma once
// What a face of the grid domain does (docs/scene-reference.md "Boundaries"): the boundary layer's
// own input, which the scene reader fills in for each of the six faces.
namespace talus {

// Periodic: paired with the opposite face (x and y only); no wall, the grid wraps instead
// (GridGeometry::periodic).
enum class WallType { Open, Slip, Fixed, Friction, Periodic };

struct WallSpec {
  WallType type = WallType::Slip;
  double friction_coefficient = 0.0;  // mu, only for Friction
};

const char* to_string(WallType type);

/// The scene's name of the face walls[axis][side]: "x-", "x+", ..., "z+" (side 0 is the lower face).
const char* face_name(int axis, int side);

}  // namespace talus
