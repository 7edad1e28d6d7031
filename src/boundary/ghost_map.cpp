#include "talus/boundary/ghost_map.hpp"

#include <algorithm>
#include <limits>
#include <stdexcept>

namespace talus {

GhostMap::GhostMap(const Walls& walls, const Grid& grid) {
  if (walls.has_mirrored_walls()) tiles_.resize(grid.tile_count());
}

void GhostMap::list_active_tiles(const Walls& walls, const Grid& grid) {
  if (tiles_.empty()) return;
  for (const std::uint32_t tile : grid.active_tiles()) {
    Tile& entry = tiles_[tile];
    if (entry.fold_begin != kUnlisted) continue;
    entry.fold_begin = static_cast<std::uint32_t>(folds_.size());
    entry.mirror_begin = static_cast<std::uint32_t>(mirrors_.size());
    const std::array<int, 3> first = grid.node_of(tile);
    if (!walls.near_mirrored_face(first, kTileEdge)) continue;  // listed, with nothing to do
    const std::size_t base = static_cast<std::size_t>(tile) * kTileNodes;
    for (int s = 0; s < kTileNodes; ++s) {
      const std::array<int, 3> node = Grid::node_in_tile(first, s);
      const std::size_t n = base + static_cast<std::size_t>(s);
      Walls::GhostNodes ghosts;
      Walls::GhostSigns signs;
      const int count = walls.ghosts_of(node, ghosts, signs);
      for (int g = 0; g < count; ++g) {
        // The ghost phase (grid_update.cpp) mirrors a ghost from its image's fold pair: the fold's
        // factors must be the mirror's.
        std::array<int, 3> image;
        std::array<double, 3> sign;
        if (!walls.mirror(ghosts[g], image, sign) || image != node || sign != signs[g])
          throw std::logic_error("GhostMap: a ghost's fold and mirror disagree");
        folds_.push_back({n, grid.node(ghosts[g][0], ghosts[g][1], ghosts[g][2]), signs[g], true});
      }
      std::array<int, 3> image;
      std::array<double, 3> sign;
      if (walls.mirror(node, image, sign)) {
        const int folded_by_image = walls.ghosts_of(image, ghosts, signs);
        const bool folded = std::find(ghosts.begin(), ghosts.begin() + folded_by_image, node) != ghosts.begin() + folded_by_image;
        mirrors_.push_back({n, grid.node(image[0], image[1], image[2]), sign, folded});
      }
    }
    if (folds_.size() >= kUnlisted || mirrors_.size() >= kUnlisted)
      throw std::length_error("GhostMap: more than 2^32 ghost pairs");
    entry.folds = static_cast<std::uint16_t>(folds_.size() - entry.fold_begin);
    entry.mirrors = static_cast<std::uint16_t>(mirrors_.size() - entry.mirror_begin);
  }
  mirrors_after_barrier_ = false;
  for (const std::uint32_t tile : grid.active_tiles())
    for (const Pair& pair : mirrors(tile))
      if (!pair.folded && pair.other / kTileNodes != tile && grid.tile_active(pair.other / kTileNodes))
        mirrors_after_barrier_ = true;
}

std::span<const GhostMap::Pair> GhostMap::folds(std::uint32_t tile) const {
  if (tiles_.empty()) return {};
  const Tile& t = tiles_[tile];
  if (t.fold_begin == kUnlisted) throw std::logic_error("GhostMap: a tile that was never listed");
  return {folds_.data() + t.fold_begin, t.folds};
}

std::span<const GhostMap::Pair> GhostMap::mirrors(std::uint32_t tile) const {
  if (tiles_.empty()) return {};
  const Tile& t = tiles_[tile];
  if (t.fold_begin == kUnlisted) throw std::logic_error("GhostMap: a tile that was never listed");
  return {mirrors_.data() + t.mirror_begin, t.mirrors};
}

std::size_t GhostMap::bytes() const {
  return tiles_.capacity() * sizeof(Tile) + (folds_.capacity() + mirrors_.capacity()) * sizeof(Pair);
}

}  // namespace talus
