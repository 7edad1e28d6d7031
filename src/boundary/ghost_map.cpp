#include "talus/boundary/ghost_map.hpp"

#include <limits>
#include <stdexcept>

namespace talus {

GhostMap::GhostMap(const Walls& walls, const Grid& grid) {
  if (!walls.has_mirrored_walls()) return;
  const std::size_t tiles = grid.tile_count();
  fold_begin_.resize(tiles + 1);
  mirror_begin_.resize(tiles + 1);
  for (std::size_t tile = 0; tile < tiles; ++tile) {
    fold_begin_[tile] = static_cast<std::uint32_t>(folds_.size());
    mirror_begin_[tile] = static_cast<std::uint32_t>(mirrors_.size());
    const std::array<int, 3> first = grid.node_of(tile);
    if (!walls.near_mirrored_face(first, kTileEdge)) continue;
    const std::size_t base = tile * kTileNodes;
    for (int s = 0; s < kTileNodes; ++s) {
      const std::array<int, 3> node = Grid::node_in_tile(first, s);
      const std::size_t n = base + static_cast<std::size_t>(s);
      std::array<std::array<int, 3>, 7> ghosts;
      std::array<std::array<double, 3>, 7> signs;
      const int count = walls.ghosts_of(node, ghosts, signs);
      for (int g = 0; g < count; ++g) folds_.push_back({n, grid.node(ghosts[g][0], ghosts[g][1], ghosts[g][2]), signs[g]});
      std::array<int, 3> image;
      std::array<double, 3> sign;
      if (walls.mirror(node, image, sign)) mirrors_.push_back({n, grid.node(image[0], image[1], image[2]), sign});
    }
    if (folds_.size() > std::numeric_limits<std::uint32_t>::max() ||
        mirrors_.size() > std::numeric_limits<std::uint32_t>::max())
      throw std::length_error("GhostMap: more than 2^32 ghost pairs");
  }
  fold_begin_[tiles] = static_cast<std::uint32_t>(folds_.size());
  mirror_begin_[tiles] = static_cast<std::uint32_t>(mirrors_.size());
}

std::size_t GhostMap::bytes() const {
  return (fold_begin_.capacity() + mirror_begin_.capacity()) * sizeof(std::uint32_t) +
         (folds_.capacity() + mirrors_.capacity()) * sizeof(Pair);
}

}  // namespace talus
