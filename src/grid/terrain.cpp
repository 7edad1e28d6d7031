#include "talus/grid/terrain.hpp"

#include "talus/grid/terrain_profile.hpp"

namespace talus {

ProfileTerrain::ProfileTerrain(const TerrainProfile& profile, double x0, double h, int pad, int columns)
    : x0_(x0), inv_h_(1.0 / h), pad_(pad) {
  z_.resize(columns);
  for (int i = 0; i < columns; ++i) z_[i] = profile.height(x0 + (i - pad) * h);
  cell_slope_.resize(columns - 1);
  std::vector<Vec3> edge_normal(columns - 1);
  for (int i = 0; i + 1 < columns; ++i) {
    cell_slope_[i] = (z_[i + 1] - z_[i]) / h;
    edge_normal[i] = Vec3(-cell_slope_[i], 0.0, 1.0).normalized();
  }
  normal_.resize(columns);
  for (int i = 0; i < columns; ++i) {
    if (i == 0) normal_[i] = edge_normal[0];
    else if (i == columns - 1) normal_[i] = edge_normal[columns - 2];
    else normal_[i] = (edge_normal[i - 1] + edge_normal[i]).normalized();  // kink: the normalised average
  }
}

}  // namespace talus
