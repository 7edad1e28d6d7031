#pragma once
// The mirrored ghost nodes of a grid, listed once per tile (issue 18: the node loops' own cost).
//
// The ghost fold and the mirror (solver/grid_update.hpp) asked Walls::ghosts_of and Walls::mirror
// for every node of every tile near a mirrored wall, four times a step. On a thin domain every tile
// is near one: the plane-strain column collapse (one cell across y, slip walls on both sides) spent
// a quarter of its step there. The walls and the grid's geometry do not change during a run, so the
// answers are listed once, per tile and in the order those loops visit them (slot by slot, and each
// node's ghosts in ghosts_of's order): the fold and the mirror do the same operations in the same
// order, and give the same bits.
#include "talus/boundary/walls.hpp"
#include "talus/grid/grid.hpp"

#include <array>
#include <cstddef>
#include <cstdint>
#include <span>
#include <vector>

namespace talus {

class GhostMap {
 public:
  /// A ghost node and its interior image, with the mirror's factor per velocity component.
  struct Pair {
    std::size_t node;   // fold: the image (the tile's node); mirror: the ghost (the tile's node)
    std::size_t other;  // fold: the ghost whose fields move to the image; mirror: the image it copies
    std::array<double, 3> sign;
  };

  GhostMap() = default;
  /// Every tile of `grid` near a mirrored wall of `walls` (none without mirrored walls).
  GhostMap(const Walls& walls, const Grid& grid);

  bool empty() const { return fold_begin_.empty(); }
  /// The folds of tile `tile` (a grid tile index): for each of its nodes in slot order, the ghosts
  /// whose image it is (Walls::ghosts_of).
  std::span<const Pair> folds(std::uint32_t tile) const { return range(folds_, fold_begin_, tile); }
  /// The mirrors of tile `tile`: each of its nodes that is a ghost, in slot order, with its image
  /// (Walls::mirror).
  std::span<const Pair> mirrors(std::uint32_t tile) const { return range(mirrors_, mirror_begin_, tile); }
  std::size_t bytes() const;

 private:
  static std::span<const Pair> range(const std::vector<Pair>& pairs, const std::vector<std::uint32_t>& begin,
                                     std::uint32_t tile) {
    if (begin.empty()) return {};
    return {pairs.data() + begin[tile], pairs.data() + begin[tile + 1]};
  }

  std::vector<std::uint32_t> fold_begin_, mirror_begin_;  // per tile, and one past the last
  std::vector<Pair> folds_, mirrors_;
};

}  // namespace talus
