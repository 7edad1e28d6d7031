#pragma once
// The mirrored ghost nodes of a grid, listed once per tile (issue 18: the node loops' own cost).
//
// The ghost fold and the mirror (solver/grid_update.hpp) asked Walls::ghosts_of and Walls::mirror
// for every node of every tile near a mirrored wall, four times a step. On a thin domain every tile
// is near one: the plane-strain column collapse (one cell across y, slip walls on both sides) spent
// a quarter of its step there. The walls and the grid's geometry do not change during a run, so the
// answers are listed once per tile, in the order those loops visit them (slot by slot, and each
// node's ghosts in ghosts_of's order): the fold and the mirror do the same operations in the same
// order, and give the same bits.
//
// A tile is listed when it first becomes active (list_active_tiles, after each sort), so the lists
// grow with the ground the flow covers, not with the grid: a small body in a long walled grid
// holds only its own tiles' ghosts. Memory: 12 B per grid tile, and 48 B per ghost of a listed tile.
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
  /// A ghost node and its image, with the mirror's factor per velocity component.
  struct Pair {
    std::size_t node;   // fold: the image (the tile's node); mirror: the ghost (the tile's node)
    std::size_t other;  // fold: the ghost whose fields move to the image; mirror: the image it copies
    std::array<double, 3> sign;
    // mirror: whether the image folds this ghost (every ghost a particle can reach; not those in the
    // tiles' slack beyond the padded grid, Walls::ghosts_of); fold: true
    bool folded;
  };

  GhostMap() = default;
  /// For `grid`'s tiles and `walls` (nothing to list without mirrored walls).
  GhostMap(const Walls& walls, const Grid& grid);

  /// Lists the grid's active tiles that are not listed yet, and notes whether mirrors_after_barrier()
  /// (serial; after each sort).
  void list_active_tiles(const Walls& walls, const Grid& grid);
  /// Whether an active tile holds a ghost that is not folded and whose image lies on another active
  /// tile: the node phase mirrors those after a barrier (solver/grid_update.hpp). Every ghost that
  /// a particle's support reaches is folded (Walls::ghosts_of); the unfolded ones lie in the tiles'
  /// slack beyond the padded grid, so this is true only where such a tile is active.
  bool mirrors_after_barrier() const { return mirrors_after_barrier_; }

  bool empty() const { return tiles_.empty(); }
  /// The folds of listed tile `tile` (a grid tile index): for each of its nodes in slot order, the
  /// ghosts whose image it is (Walls::ghosts_of).
  std::span<const Pair> folds(std::uint32_t tile) const;
  /// The mirrors of listed tile `tile`: each of its nodes that is a ghost, in slot order, with its
  /// image (Walls::mirror).
  std::span<const Pair> mirrors(std::uint32_t tile) const;
  std::size_t bytes() const;
  /// The bytes the map holds per tile of the grid, before any tile is listed.
  static constexpr std::size_t kBytesPerTile = 12;

 private:
  struct Tile {
    std::uint32_t fold_begin = kUnlisted, mirror_begin = 0;
    std::uint16_t folds = 0, mirrors = 0;  // at most 7 and 1 per node of 64
  };
  static constexpr std::uint32_t kUnlisted = 0xffffffffu;
  static_assert(sizeof(Tile) == kBytesPerTile);

  std::vector<Tile> tiles_;
  std::vector<Pair> folds_, mirrors_;
  bool mirrors_after_barrier_ = false;
};

}  // namespace talus
