#include "talus/diagnostics/flume_coordinates.hpp"

#include <cmath>

namespace talus {

FlumeCoordinates flume_coordinates_of(const Scene& scene) {
  return scene.grid.has_terrain() ? FlumeCoordinates(TerrainProfile(scene.grid.terrain)) : FlumeCoordinates();
}

std::optional<double> FlumeCoordinates::last_segment_start() const {
  if (!profile_) return std::nullopt;
  const TerrainSpec& spec = profile_->spec();
  const std::size_t n = spec.points.size();
  if (n < 3) return std::nullopt;
  const auto& a = spec.points[n - 3];
  const auto& v = spec.points[n - 2];  // the last interior vertex
  const auto& b = spec.points[n - 1];
  const double r = spec.radii.empty() ? 0.0 : spec.radii[n - 2];
  const double in = std::atan2(v[1] - a[1], v[0] - a[0]);
  const double out = std::atan2(b[1] - v[1], b[0] - v[0]);
  // A fillet of radius r tangent to both segments touches them at the distance r tan(|turn| / 2)
  // from the vertex (the tangent length of a circular curve).
  const double tangent_length = r * std::tan(0.5 * std::abs(out - in));
  return v[0] + tangent_length * std::cos(out);
}

}  // namespace talus
