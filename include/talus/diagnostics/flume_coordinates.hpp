#pragma once
// FlumeCoordinates: the coordinate along the flume in which runout is measured. On a terrain it is
// the bed's arc length s(x) (TerrainProfile::arc_length, s = 0 at the first terrain vertex); on a
// flat grid s = x. The bed tangent t(x) = (1, z_b'(x)) / sqrt(1 + z_b'^2) points down-flume (+x).
// The runout is uniform across the width, so s depends on x only.
#include "talus/core/types.hpp"
#include "talus/grid/terrain_profile.hpp"
#include "talus/scene/scene.hpp"

#include <cmath>
#include <optional>

namespace talus {

class FlumeCoordinates;

/// The flume coordinates of a scene: its terrain's, or flat when it has none. (Until the terrain
/// branch adds grid.terrain to the scene, every scene is flat: this is the one place to connect it.)
FlumeCoordinates flume_coordinates_of(const Scene& scene);

class FlumeCoordinates {
 public:
  /// A flat bed: s = x, tangent (1, 0, 0).
  FlumeCoordinates() = default;
  explicit FlumeCoordinates(TerrainProfile profile) : profile_(std::move(profile)) {}

  bool flat() const { return !profile_.has_value(); }
  /// The terrain (only when !flat()).
  const TerrainProfile& profile() const { return *profile_; }
  double s(double x) const { return profile_ ? profile_->arc_length(x) : x; }
  double x_at(double s) const { return profile_ ? profile_->x_at_arc_length(s) : s; }
  Vec3 tangent(double x) const {
    const double k = profile_ ? profile_->slope(x) : 0.0;
    return Vec3(1.0, 0.0, k) / std::sqrt(1.0 + k * k);
  }
  /// x where the last straight segment of the terrain begins: the end of the last transition (the
  /// tangent point of its fillet), or the last interior vertex when it is a sharp kink. For the
  /// flume that is the start of the runout plane. Empty on a flat bed or a one-segment terrain.
  std::optional<double> last_segment_start() const;

 private:
  std::optional<TerrainProfile> profile_;
};

}  // namespace talus
