// GhostMap (boundary/ghost_map.hpp): the walls' ghost nodes listed once per tile must be exactly what
// Walls::ghosts_of and Walls::mirror answer node by node, in the order the fold and the mirror visit
// them (slot by slot, each node's ghosts in ghosts_of's order), on every tile of the grid, whichever
// order the tiles become active in.
#include "talus/boundary/ghost_map.hpp"

#include <gtest/gtest.h>

#include <stdexcept>
#include <vector>

namespace talus {
namespace ghost_map_test {
namespace {

struct Case {
  const char* name;
  std::array<int, 3> cells;
  std::array<std::array<WallType, 2>, 3> types;
};

/// Checks every tile of the grid against Walls node by node; returns the number of folds seen, and
/// in `unfolded` the mirrored ghosts no fold takes. Those lie only in the tiles' slack beyond the
/// padded grid (more than kPad nodes past a face), where no particle's support reaches: every
/// ghost a particle can reach is folded into its image, also when the image lies beyond a face
/// that is not mirrored (under a frictional floor, past an open face), which it did not before
/// 2026-12-05 (the energy gap terms found it: tests/solver/energy_gap_test.cpp).
std::size_t expect_same_as_walls(const Case& c, std::size_t& unfolded) {
  GridGeometry g;
  g.h = 0.01;
  g.cells = c.cells;
  std::array<std::array<WallSpec, 2>, 3> specs{};
  for (int d = 0; d < 3; ++d)
    for (int s = 0; s < 2; ++s) specs[d][s] = {c.types[d][s], 0.3};
  const Walls walls(specs, g);
  Grid grid(g);
  GhostMap map(walls, grid);
  // the tiles become active in two sorts: the odd ones first (listed once), then all, backwards
  std::vector<std::uint32_t> odd, all;
  for (std::uint32_t t = 0; t < grid.tile_count(); ++t) {
    if (t % 2 == 1) odd.push_back(t);
    all.insert(all.begin(), t);
  }
  grid.set_active_tiles(odd);
  map.list_active_tiles(walls, grid);
  grid.set_active_tiles(odd);
  map.list_active_tiles(walls, grid);  // nothing new
  grid.set_active_tiles(all);
  map.list_active_tiles(walls, grid);
  std::size_t folds = 0;
  for (std::size_t tile = 0; tile < grid.tile_count(); ++tile) {
    std::vector<GhostMap::Pair> fold, mirror;
    const std::array<int, 3> first = grid.node_of(tile);
    for (int s = 0; s < kTileNodes; ++s) {
      const std::array<int, 3> node = Grid::node_in_tile(first, s);
      const std::size_t n = tile * kTileNodes + static_cast<std::size_t>(s);
      Walls::GhostNodes ghosts;
      Walls::GhostSigns signs;
      const int count = walls.ghosts_of(node, ghosts, signs);
      for (int k = 0; k < count; ++k)
        fold.push_back({n, grid.node(ghosts[k][0], ghosts[k][1], ghosts[k][2]), signs[k], true});
      std::array<int, 3> image;
      std::array<double, 3> sign;
      if (walls.mirror(node, image, sign)) {
        // folded: the image's fold takes this ghost
        const int by_image = walls.ghosts_of(image, ghosts, signs);
        bool folded = false;
        for (int k = 0; k < by_image; ++k) folded = folded || ghosts[k] == node;
        mirror.push_back({n, grid.node(image[0], image[1], image[2]), sign, folded});
        unfolded += folded ? 0 : 1;
        bool beyond_the_pad = false;
        for (int d = 0; d < 3; ++d) beyond_the_pad = beyond_the_pad || node[d] > kPad + c.cells[d] + kPad;
        EXPECT_TRUE(folded || beyond_the_pad) << c.name << ": ghost (" << node[0] << ", " << node[1] << ", "
                                              << node[2] << ") is not folded";
      }
    }
    const auto listed_folds = map.folds(static_cast<std::uint32_t>(tile));
    const auto listed_mirrors = map.mirrors(static_cast<std::uint32_t>(tile));
    EXPECT_EQ(listed_folds.size(), fold.size()) << c.name << ", tile " << tile;
    EXPECT_EQ(listed_mirrors.size(), mirror.size()) << c.name << ", tile " << tile;
    for (std::size_t i = 0; i < std::min(fold.size(), listed_folds.size()); ++i) {
      EXPECT_EQ(listed_folds[i].node, fold[i].node) << c.name << ", tile " << tile << ", fold " << i;
      EXPECT_EQ(listed_folds[i].other, fold[i].other) << c.name << ", tile " << tile << ", fold " << i;
      EXPECT_EQ(listed_folds[i].sign, fold[i].sign) << c.name << ", tile " << tile << ", fold " << i;
      EXPECT_EQ(listed_folds[i].folded, fold[i].folded) << c.name << ", tile " << tile << ", fold " << i;
    }
    for (std::size_t i = 0; i < std::min(mirror.size(), listed_mirrors.size()); ++i) {
      EXPECT_EQ(listed_mirrors[i].node, mirror[i].node) << c.name << ", tile " << tile << ", mirror " << i;
      EXPECT_EQ(listed_mirrors[i].other, mirror[i].other) << c.name << ", tile " << tile << ", mirror " << i;
      EXPECT_EQ(listed_mirrors[i].sign, mirror[i].sign) << c.name << ", tile " << tile << ", mirror " << i;
      EXPECT_EQ(listed_mirrors[i].folded, mirror[i].folded) << c.name << ", tile " << tile << ", mirror " << i;
    }
    folds += fold.size();
  }
  return folds;
}

constexpr WallType F = WallType::Fixed, S = WallType::Slip, O = WallType::Open, C = WallType::Friction;

TEST(GhostMap, ListsWhatTheWallsAnswerOnEveryTile) {
  // a thin plane-strain slice (one cell across y, both sides mirrored: two ghosts per node), a box
  // with fixed walls (corners: up to 7 ghosts per node), mixed walls, a domain narrower than the pad
  const Case cases[] = {
      {"plane strain slice", {20, 1, 9}, {{{S, S}, {S, S}, {C, O}}}},
      {"fixed box", {6, 7, 5}, {{{F, F}, {F, F}, {F, F}}}},
      {"mixed", {9, 3, 6}, {{{F, O}, {S, C}, {S, F}}}},
      {"thin fixed", {2, 1, 3}, {{{F, S}, {S, F}, {F, S}}}},
  };
  std::size_t unfolded = 0;
  for (const Case& c : cases) EXPECT_GT(expect_same_as_walls(c, unfolded), 0u) << c.name;
  EXPECT_GT(unfolded, 0u);  // in the tiles' slack beyond the pad
}

/// A grid of `cells` and its walls, every face of type `type` (the z- face of type `floor`).
struct Box {
  Box(std::array<int, 3> cells, WallType type, WallSpec floor) : geometry(with_cells(cells)), grid(geometry) {
    std::array<std::array<WallSpec, 2>, 3> specs{};
    for (auto& axis : specs)
      for (auto& side : axis) side = {type, 0.0};
    specs[2][0] = floor;
    walls = Walls(specs, geometry);
  }
  static GridGeometry with_cells(std::array<int, 3> cells) {
    GridGeometry g;
    g.cells = cells;
    return g;
  }
  GridGeometry geometry;
  Grid grid;
  Walls walls;
};

TEST(GhostMap, ListsATileWhenItFirstBecomesActive) {
  Box box({12, 1, 8}, WallType::Slip, {WallType::Slip, 0.0});
  GhostMap map(box.walls, box.grid);
  const std::size_t empty_bytes = map.bytes();
  EXPECT_EQ(empty_bytes, box.grid.tile_count() * GhostMap::kBytesPerTile);
  box.grid.set_active_tiles({0});
  map.list_active_tiles(box.walls, box.grid);
  EXPECT_GT(map.bytes(), empty_bytes);
  EXPECT_FALSE(map.folds(0).empty());
  EXPECT_THROW(map.folds(1), std::logic_error);  // never active: not listed
  box.grid.set_active_tiles({0, 1});
  map.list_active_tiles(box.walls, box.grid);
  EXPECT_FALSE(map.folds(1).empty());  // every tile of this thin box is near a wall
}

TEST(GhostMap, IsEmptyWithoutMirroredWalls) {
  Box box({5, 5, 5}, WallType::Open, {WallType::Friction, 0.5});  // a unilateral floor is not mirrored
  box.grid.set_active_tiles({0, 1, 2});
  GhostMap map(box.walls, box.grid);
  map.list_active_tiles(box.walls, box.grid);
  EXPECT_TRUE(map.empty());
  EXPECT_TRUE(map.folds(0).empty());
  EXPECT_TRUE(map.mirrors(0).empty());
}

}  // namespace
}  // namespace ghost_map_test
}  // namespace talus
