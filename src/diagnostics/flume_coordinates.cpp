#include "talus/diagnostics/flume_coordinates.hpp"

#include <cmath>

namespace talus {

FlumeCoordinates flume_coordinates_of(const Scene& scene) {
  return scene.grid.has_terrain() ? FlumeCoordinates(TerrainProfile(scene.grid.terrain)) : FlumeCoordinates();
}

std::optional<double> FlumeCoordinates::last_segment_start() const {
  return profile_ ? profile_->last_segment_start() : std::nullopt;
}

}  // namespace talus
