#include "talus/grid/grid.hpp"

#include <algorithm>

namespace talus {

ProfileTerrain grid_bed(const GridGeometry& g) {
  if (!g.has_terrain()) return ProfileTerrain();
  return ProfileTerrain(TerrainProfile(g.terrain), g.origin[0], g.h, kPad, g.nodes()[0]);
}

Grid::Grid(const GridGeometry& geometry) : geometry_(geometry), profile_(grid_bed(geometry)) {
  const auto n = geometry.nodes();
  for (int d = 0; d < 3; ++d) tiles_[d] = (n[d] + kTileEdge - 1) / kTileEdge;
  stride_y_ = static_cast<std::size_t>(tiles_[2]) * kTileNodes;
  stride_x_ = static_cast<std::size_t>(tiles_[1]) * stride_y_;
  const std::size_t count = tile_count() * kTileNodes;
  tile_active_.assign(tile_count(), 0);
  records_ = LazyArray(count * kNodeRecord);
  lagrangian_ = LazyArray(count * kLagrangianRecord);
  double* r = records_.data();
  mass = NodeField(r + kMassSlot, kNodeRecord);
  for (int d = 0; d < 3; ++d) {
    momentum[d] = NodeField(r + kMomentumSlot + d, kNodeRecord);
    force[d] = NodeField(r + kForceSlot + d, kNodeRecord);
    velocity_l[d] = NodeField(lagrangian_.data() + d, kLagrangianRecord);
  }
}

std::array<int, 3> Grid::node_of(std::size_t tile) const {
  const int tk = static_cast<int>(tile % tiles_[2]);
  const int tj = static_cast<int>((tile / tiles_[2]) % tiles_[1]);
  const int ti = static_cast<int>(tile / (static_cast<std::size_t>(tiles_[2]) * tiles_[1]));
  return {ti * kTileEdge, tj * kTileEdge, tk * kTileEdge};
}

void Grid::set_active_tiles(std::vector<std::uint32_t> tiles) {
  for (std::uint32_t t : active_tiles_) tile_active_[t] = 0;
  active_tiles_ = std::move(tiles);
  for (std::uint32_t t : active_tiles_) tile_active_[t] = 1;
}

void Grid::clear_tile(std::size_t tile) {
  const std::size_t begin = tile * kTileNodes;
  std::fill_n(records_.data() + begin * kNodeRecord, kTileNodes * kNodeRecord, 0.0);
  std::fill_n(lagrangian_.data() + begin * kLagrangianRecord, kTileNodes * kLagrangianRecord, 0.0);
}

void Grid::clear_active() {
  const auto& tiles = active_tiles_;
  const std::size_t count = tiles.size();
#pragma omp parallel for schedule(static)
  for (std::size_t t = 0; t < count; ++t) clear_tile(tiles[t]);
}

void Grid::clear_momentum() {
  const auto& tiles = active_tiles_;
  const std::size_t count = tiles.size();
#pragma omp parallel for schedule(static)
  for (std::size_t t = 0; t < count; ++t) {
    const std::size_t begin = static_cast<std::size_t>(tiles[t]) * kTileNodes;
    for (int s = 0; s < kTileNodes; ++s) {
      double* node = record(begin + s);
      for (int d = 0; d < 3; ++d) node[kMomentumSlot + d] = 0.0;
    }
  }
}

std::size_t Grid::active_bytes() const {
  return active_tiles_.size() * kTileNodes * kFieldCount * sizeof(double);
}

}  // namespace talus
