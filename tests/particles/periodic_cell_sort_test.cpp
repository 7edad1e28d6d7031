// The cell sort on periodic axes (cell_sort.hpp): the blocks tile the domain from its first cell,
// the blocks of one colour never write a common node even where the stencils wrap around the seam
// and every particle has drifted its full slack, and the active tiles hold every node written.
#include "talus/core/error.hpp"
#include "talus/particles/cell_sort.hpp"

#include <gtest/gtest.h>

#include <random>
#include <set>

namespace talus {
namespace periodic_cell_sort_test {
namespace {

TEST(PeriodicCellSort, BlocksOfOneColourWriteDisjointNodesAcrossTheSeam) {
  struct Case {
    int reach_low, reach_high;
    std::array<int, 3> cells;
  };
  // linear (blocks of 4) and the wider supports (blocks of 8); x with 2 and 4 blocks, y with 1
  for (const Case c : {Case{0, 1, {8, 4, 6}}, Case{0, 1, {16, 4, 6}}, Case{1, 2, {16, 8, 6}}, Case{1, 2, {32, 8, 6}}}) {
    SCOPED_TRACE(c.cells[0]);
    GridGeometry g;
    g.h = 0.1;
    g.cells = c.cells;
    g.periodic = {true, true, false};
    Grid grid(g);
    ParticleStore particles;
    std::mt19937 rng(11);
    std::uniform_real_distribution<double> u(0.0, 1.0);
    for (int p = 0; p < 4000; ++p)
      particles.add(p, Vec3(0.1 * c.cells[0] * u(rng), 0.1 * c.cells[1] * u(rng), 0.1 * c.cells[2] * u(rng)),
                    Vec3::Zero(), 1.0, 1e-3, 0);
    CellSort sort(grid, c.reach_low, c.reach_high);
    sort.sort(particles, grid);
    const int bc = sort.block_cells(), slack = sort.slack();
    // every block along the periodic axes holds particles; along z those over the domain's cells
    const int z_blocks = (kPad + c.cells[2] - 1) / bc - kPad / bc + 1;
    ASSERT_EQ(sort.block_count(), static_cast<std::size_t>(c.cells[0] / bc) * (c.cells[1] / bc) * z_blocks);
    std::set<std::uint32_t> active(grid.active_tiles().begin(), grid.active_tiles().end());
    for (int colour = 0; colour < 8; ++colour) {
      std::set<std::size_t> written;  // by the blocks of this colour so far
      for (std::uint32_t b : sort.colour(colour)) {
        const auto o = sort.block_origin(b);
        for (int d = 0; d < 2; ++d) EXPECT_EQ((o[d] - kPad) % bc, 0);  // blocks start at the domain's first cell
        std::set<std::size_t> mine;
        for (int i = o[0] - slack - c.reach_low; i <= o[0] + bc - 1 + slack + c.reach_high; ++i)
          for (int j = o[1] - slack - c.reach_low; j <= o[1] + bc - 1 + slack + c.reach_high; ++j)
            for (int k = std::max(0, o[2] - slack - c.reach_low); k <= std::min(g.nodes()[2] - 1, o[2] + bc - 1 + slack + c.reach_high); ++k) {
              const int wi = g.wrap_node(0, i), wj = g.wrap_node(1, j);
              ASSERT_GE(wi, kPad);
              ASSERT_LT(wi, kPad + c.cells[0]);
              const std::size_t n = grid.node(wi, wj, k);
              mine.insert(n);
              const std::size_t tile = (static_cast<std::size_t>(wi / kTileEdge) * grid.tiles()[1] + wj / kTileEdge) * grid.tiles()[2] + k / kTileEdge;
              ASSERT_TRUE(active.count(static_cast<std::uint32_t>(tile))) << "node " << wi << " " << wj << " " << k;
            }
        for (std::size_t n : mine) ASSERT_TRUE(written.insert(n).second) << "colour " << colour << " block " << b;
      }
    }
  }
}

TEST(PeriodicCellSort, OddBlockCountsAreRefused) {
  GridGeometry g;
  g.h = 0.1;
  g.cells = {12, 8, 4};  // 3 blocks of 4 along x
  g.periodic = {true, false, false};
  const Grid grid(g);
  EXPECT_THROW(CellSort(grid, 0, 1), Error);
  EXPECT_TRUE(CellSort::periodic_blocks_fit(4, 4));
  EXPECT_TRUE(CellSort::periodic_blocks_fit(8, 4));
  EXPECT_FALSE(CellSort::periodic_blocks_fit(12, 4));
  EXPECT_FALSE(CellSort::periodic_blocks_fit(6, 4));
}

}  // namespace
}  // namespace periodic_cell_sort_test
}  // namespace talus
