// TileStages: the node work of a grid phase in one parallel region (grid/tile_stages.hpp).
#include "talus/grid/tile_stages.hpp"

#include <gtest/gtest.h>
#include <omp.h>

#include <numeric>
#include <vector>

namespace talus {
namespace {

TEST(TileStages, OwnTileStagesShareALoopAndEveryOtherStageHasItsOwn) {
  auto loops = [](std::initializer_list<int> kinds) {  // 0 OwnTile, 1 AnyTile, 2 another index space
    TileStages s(8);
    for (int k : kinds) {
      if (k == 2)
        s.add_loop(3, [](std::size_t) {});
      else
        s.add(k == 0 ? TileReach::OwnTile : TileReach::AnyTile, [](std::size_t) {});
    }
    return s.loops();
  };
  EXPECT_EQ(loops({}), 0);
  EXPECT_EQ(loops({0, 0, 0}), 1);       // the box sum, the grid update, the velocities: no barrier
  EXPECT_EQ(loops({0, 1, 0, 1}), 4);    // sum | fold | update | mirror (mirrored walls)
  EXPECT_EQ(loops({1, 1}), 2);
  EXPECT_EQ(loops({2, 0, 0}), 2);       // a sum over other tiles, then the update
  EXPECT_EQ(loops({0, 2, 0}), 3);
}

// With 4 threads: each OwnTile stage sees its tile's earlier stages done, and an AnyTile stage
// sees every tile's earlier stages done (a barrier), whatever thread ran them.
TEST(TileStages, EachStageSeesTheWorkItMustWaitFor) {
  const std::size_t n = 97;
  std::vector<long> a(n, 0), b(n, 0), c(n, 0);
  std::vector<int> order(n, 0);
  TileStages s(n);
  s.add(TileReach::OwnTile, [&](std::size_t t) { a[t] = static_cast<long>(t) + 1; });
  s.add(TileReach::OwnTile, [&](std::size_t t) { order[t] = a[t] == static_cast<long>(t) + 1 ? 1 : -1; });
  s.add(TileReach::AnyTile, [&](std::size_t t) { b[t] = std::accumulate(a.begin(), a.end(), 0L) + static_cast<long>(t); });
  s.add(TileReach::OwnTile, [&](std::size_t t) {
    // reads every tile's b: a barrier after the AnyTile stage
    c[t] = std::accumulate(b.begin(), b.end(), 0L);
  });
  ASSERT_EQ(s.loops(), 3);
  const int saved = omp_get_max_threads();
  omp_set_num_threads(4);
  s.run();
  omp_set_num_threads(saved);
  const long sum_a = static_cast<long>(n * (n + 1) / 2);
  const long sum_b = static_cast<long>(n) * sum_a + static_cast<long>(n * (n - 1) / 2);
  for (std::size_t t = 0; t < n; ++t) {
    EXPECT_EQ(order[t], 1) << t;
    EXPECT_EQ(b[t], sum_a + static_cast<long>(t)) << t;
    EXPECT_EQ(c[t], sum_b) << t;
  }
}

TEST(TileStages, ALoopOverAnotherIndexSpaceRunsItsOwnCount) {
  std::vector<int> hits(5, 0);
  std::vector<int> tiles(3, 0);
  TileStages s(3);
  s.add_loop(5, [&](std::size_t i) { ++hits[i]; });
  s.add(TileReach::OwnTile, [&](std::size_t t) { tiles[t] = hits[0] + hits[4]; });
  s.run();
  EXPECT_EQ(hits, std::vector<int>(5, 1));
  EXPECT_EQ(tiles, std::vector<int>(3, 2));
}

}  // namespace
}  // namespace talus
