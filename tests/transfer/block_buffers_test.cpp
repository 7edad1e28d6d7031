// BlockBuffers (transfer/block_buffers.hpp): the scatter into per-block boxes and their sum into the
// grid as a TileStages stage. When the boxes' tiles are the grid's active tiles the sum is an
// OwnTile stage (the grid update can follow on the same tile without a barrier); when they are not
// (the grid's tile list changed since the boxes were prepared) it is a loop of its own, and the node
// sums are the same bits either way.
#include "talus/grid/grid.hpp"
#include "talus/grid/terrain.hpp"
#include "talus/grid/tile_stages.hpp"
#include "talus/particles/cell_sort.hpp"
#include "talus/particles/particle_store.hpp"
#include "talus/shape/linear.hpp"
#include "talus/transfer/block_buffers.hpp"
#include "talus/transfer/transfers.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <random>
#include <stdexcept>
#include <vector>

namespace talus {
namespace block_buffers_test {
namespace {

struct Scatter {
  Grid grid;
  ParticleStore P;
  CellSort sort;
  Scatter() : grid(geometry()), sort(grid, LinearShape::kReachLow, LinearShape::kReachHigh) {
    std::mt19937 rng(5);
    std::uniform_real_distribution<double> pos(0.25, 0.95), vel(-1.0, 1.0);
    for (int i = 0; i < 3000; ++i)
      P.add(i, Vec3(pos(rng), pos(rng), pos(rng)), Vec3(vel(rng), vel(rng), vel(rng)), 1.0 + 0.5 * vel(rng), 1.25e-4, 0);
    for (int c = 0; c < 6; ++c)
      for (std::size_t p = 0; p < P.size(); ++p) P.stress[c][p] = 100.0 * vel(rng);
    sort.sort(P, grid);
  }
  static GridGeometry geometry() {
    GridGeometry g;
    g.h = 0.1;
    g.cells = {12, 12, 12};
    return g;
  }
  /// The node records of `tiles`, in order.
  std::vector<double> records(const std::vector<std::uint32_t>& tiles) const {
    std::vector<double> r;
    for (std::uint32_t t : tiles)
      for (int s = 0; s < kTileNodes; ++s)
        for (int v = 0; v < kNodeRecord; ++v) r.push_back(grid.records()[(static_cast<std::size_t>(t) * kTileNodes + s) * kNodeRecord + v]);
    return r;
  }
};

constexpr ScatteredFields kAll{.mass = true, .momentum = true, .force = true};

TEST(BlockBuffers, TheSumIsAnOwnTileStageWhenTheBoxesCoverTheActiveTiles) {
  Scatter s;
  const std::vector<std::uint32_t> active = s.grid.active_tiles();
  // the colour passes' sums, for scale: the boxes' sums differ from them by round-off only
  s.grid.clear_active();
  scatter_to_grid<LinearShape, FlatTerrain>(s.P, s.sort, s.grid, ScatterFields::MassMomentumForce);
  const std::vector<double> colours = s.records(active);

  BlockBuffers buffers;
  buffers.prepare(s.sort, s.grid);
  ASSERT_TRUE(buffers.covers_active_tiles());
  // garbage in the grid: the stage clears each tile before its sums
  for (std::uint32_t t : active) s.grid.records()[static_cast<std::size_t>(t) * kTileNodes * kNodeRecord] = 7.0;
  scatter_to_grid<LinearShape, FlatTerrain>(s.P, s.sort, s.grid, ScatterFields::MassMomentumForce, nullptr, &buffers);
  TileStages stages(active.size());
  buffers.add_sum_stage(stages, s.grid, kAll, true);
  std::vector<int> after(active.size(), 0);
  stages.add(TileReach::OwnTile, [&](std::size_t t) { after[t] = 1; });
  EXPECT_EQ(stages.loops(), 1);  // the sum and the next own-tile stage share a loop
  stages.run();
  EXPECT_EQ(after, std::vector<int>(active.size(), 1));
  const std::vector<double> boxes = s.records(active);
  ASSERT_EQ(boxes.size(), colours.size());
  double largest = 0.0;
  for (std::size_t i = 0; i < boxes.size(); ++i) {
    EXPECT_NEAR(boxes[i], colours[i], 1e-9 * (1.0 + std::abs(colours[i]))) << i;
    largest = std::max(largest, std::abs(colours[i]));
  }
  EXPECT_GT(largest, 1.0);  // real sums were compared
}

// The grid's tile list changed after prepare(): an extra tile no box reaches (the boxes no longer
// cover the active tiles), or a tile missing that a box reaches (prepare's serial way, for boxes
// outside the active list). The sum is a loop over the boxes' tiles then, and refuses to clear.
TEST(BlockBuffers, WhenTheBoxesDoNotCoverTheActiveTilesTheSumIsALoopOfItsOwnWithTheSameBits) {
  Scatter s;
  const std::vector<std::uint32_t> active = s.grid.active_tiles();
  BlockBuffers reference;
  reference.prepare(s.sort, s.grid);
  s.grid.clear_active();
  scatter_to_grid<LinearShape, FlatTerrain>(s.P, s.sort, s.grid, ScatterFields::MassMomentumForce, nullptr, &reference);
  TileStages stages(active.size());
  reference.add_sum_stage(stages, s.grid, kAll);
  stages.run();
  const std::vector<double> expected = s.records(active);

  const auto tiles = s.grid.tiles();
  const auto count = static_cast<std::uint32_t>(tiles[0] * tiles[1] * tiles[2]);
  std::uint32_t spare = 0;  // a tile no box reaches
  while (std::binary_search(active.begin(), active.end(), spare)) ++spare;
  ASSERT_LT(spare, count);
  std::vector<std::uint32_t> extra = active;
  extra.insert(std::lower_bound(extra.begin(), extra.end(), spare), spare);
  std::vector<std::uint32_t> missing(active.begin() + 1, active.end());

  for (const auto& list : {extra, missing}) {
    const char* what = list.size() > active.size() ? "an extra tile" : "a tile missing";
    s.grid.set_active_tiles(list);
    BlockBuffers buffers;
    buffers.prepare(s.sort, s.grid);
    EXPECT_FALSE(buffers.covers_active_tiles()) << what;
    TileStages refused(list.size());
    EXPECT_THROW(buffers.add_sum_stage(refused, s.grid, kAll, true), std::logic_error) << what;
    s.grid.set_active_tiles(active);
    s.grid.clear_active();
    s.grid.set_active_tiles(list);
    scatter_to_grid<LinearShape, FlatTerrain>(s.P, s.sort, s.grid, ScatterFields::MassMomentumForce, nullptr, &buffers);
    TileStages sum(list.size());
    buffers.add_sum_stage(sum, s.grid, kAll);
    sum.add(TileReach::OwnTile, [](std::size_t) {});
    EXPECT_EQ(sum.loops(), 2) << what;  // the boxes' own loop, then a barrier
    sum.run();
    EXPECT_EQ(s.records(active), expected) << what;
  }
}

}  // namespace
}  // namespace block_buffers_test
}  // namespace talus
