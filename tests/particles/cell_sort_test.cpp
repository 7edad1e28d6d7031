// CellSort (particles/cell_sort.hpp): the counting sort by (block, cell), its offsets, the stable
// order within a cell, and the colouring that lets each colour scatter without atomics.
#include "talus/particles/cell_sort.hpp"

#include <gtest/gtest.h>
#include <omp.h>

#include <algorithm>
#include <numeric>

#include <cmath>
#include <random>
#include <set>

namespace talus {
namespace cell_sort_test {
namespace {

struct SortedCloud {
  Grid grid;
  ParticleStore particles;
  CellSort sort;
  SortedCloud() {
    GridGeometry g;
    g.h = 0.1;
    g.cells = {20, 12, 9};
    grid = Grid(g);
    std::mt19937 rng(7);
    std::uniform_real_distribution<double> u(0.0, 1.0);
    for (int p = 0; p < 3000; ++p)
      particles.add(p, Vec3(2.0 * u(rng), 1.2 * u(rng), 0.9 * u(rng)), Vec3::Zero(), 1.0, 1e-3, 0);
    sort = CellSort(grid, 0, 1);  // linear shape functions: reach 0 below, 1 above
    sort.sort(particles, grid);
  }
  std::array<int, 3> cell_of(std::size_t p) const {
    std::array<int, 3> c{};
    for (int d = 0; d < 3; ++d) c[d] = static_cast<int>(std::floor(grid.geometry().to_grid(d, particles.x[d][p])));
    return c;
  }
};

TEST(CellSort, EveryParticleSitsInTheCellItsOffsetsSay) {
  const SortedCloud s;
  const int bc = s.sort.block_cells();
  const std::size_t cells_per_block = static_cast<std::size_t>(bc) * bc * bc;
  std::size_t seen = 0;
  for (std::size_t b = 0; b < s.sort.block_count(); ++b) {
    const auto o = s.sort.block_origin(b);
    EXPECT_EQ(s.sort.cell_start()[b * cells_per_block], s.sort.block_begin(b));
    for (std::size_t l = 0; l < cells_per_block; ++l) {
      const int li = static_cast<int>(l / (bc * bc)), lj = static_cast<int>((l / bc) % bc), lk = static_cast<int>(l % bc);
      for (std::uint32_t p = s.sort.cell_start()[b * cells_per_block + l]; p < s.sort.cell_start()[b * cells_per_block + l + 1]; ++p) {
        EXPECT_EQ(s.cell_of(p), (std::array<int, 3>{o[0] + li, o[1] + lj, o[2] + lk})) << "particle " << p;
        ++seen;
      }
    }
  }
  EXPECT_EQ(seen, s.particles.size());
}

// The blocks by their coordinates (CellSort::active_block, which the MLS search walks with): every
// active block is found from its origin, and every other coordinate, outside the bounding box too,
// gives -1. On periodic axes the blocks start at the domain's first cell (block_shift() = kPad).
void expect_blocks_found_by_coordinates(const CellSort& sort) {
  const int bc = sort.block_cells();
  std::set<std::array<int, 3>> origins;
  for (std::size_t b = 0; b < sort.block_count(); ++b) {
    const auto o = sort.block_origin(b);
    std::array<int, 3> c{};
    for (int d = 0; d < 3; ++d) {
      ASSERT_EQ((o[d] - sort.block_shift()[d]) % bc, 0) << "block " << b;
      c[d] = (o[d] - sort.block_shift()[d]) / bc;
    }
    EXPECT_EQ(sort.active_block(c[0], c[1], c[2]), static_cast<long long>(b));
    origins.insert(c);
  }
  std::size_t found = 0;
  for (int i = -2; i < 12; ++i)
    for (int j = -2; j < 12; ++j)
      for (int k = -2; k < 12; ++k) {
        const long long b = sort.active_block(i, j, k);
        EXPECT_EQ(b >= 0, origins.count({i, j, k}) == 1) << i << " " << j << " " << k;
        found += b >= 0 ? 1 : 0;
      }
  EXPECT_EQ(found, sort.block_count());
}

TEST(CellSort, EveryActiveBlockIsFoundByItsCoordinates) {
  const SortedCloud s;
  EXPECT_EQ(s.sort.block_shift(), (std::array<int, 3>{0, 0, 0}));
  expect_blocks_found_by_coordinates(s.sort);
  GridGeometry g;  // periodic along x: the blocks start at cell kPad
  g.h = 0.1;
  g.cells = {16, 8, 6};
  g.periodic = {true, false, false};
  Grid grid(g);
  ParticleStore particles;
  std::mt19937 rng(3);
  std::uniform_real_distribution<double> u(0.0, 1.0);
  for (int p = 0; p < 500; ++p) particles.add(p, Vec3(1.6 * u(rng), 0.4 * u(rng), 0.3 * u(rng)), Vec3::Zero(), 1.0, 1e-3, 0);
  CellSort sort(grid, 0, 1);
  sort.sort(particles, grid);
  EXPECT_EQ(sort.block_shift(), (std::array<int, 3>{kPad, 0, 0}));
  expect_blocks_found_by_coordinates(sort);
}

TEST(CellSort, TheSortIsStableAndAPermutation) {
  const SortedCloud s;
  std::set<std::int64_t> ids(s.particles.id.begin(), s.particles.id.end());
  EXPECT_EQ(ids.size(), 3000u);
  // Particles were added in id order; within a cell the counting sort keeps that order.
  for (std::size_t p = 1; p < s.particles.size(); ++p) {
    if (s.cell_of(p) == s.cell_of(p - 1)) {
      EXPECT_LT(s.particles.id[p - 1], s.particles.id[p]);
    }
  }
}

TEST(CellSort, BlocksOfOneColourAreNeverNeighbours) {
  const SortedCloud s;
  const int bc = s.sort.block_cells();
  std::set<std::uint32_t> all;
  for (int c = 0; c < 8; ++c) {
    const auto& blocks = s.sort.colour(c);
    for (std::uint32_t b : blocks) EXPECT_TRUE(all.insert(b).second) << "block in two colours";
    for (std::size_t i = 0; i < blocks.size(); ++i)
      for (std::size_t j = i + 1; j < blocks.size(); ++j) {
        const auto a = s.sort.block_origin(blocks[i]), b = s.sort.block_origin(blocks[j]);
        bool apart = false;  // one block between them along some axis: their writes never meet
        for (int d = 0; d < 3; ++d) apart = apart || std::abs(a[d] - b[d]) >= 2 * bc;
        EXPECT_TRUE(apart) << "colour " << c;
      }
  }
  EXPECT_EQ(all.size(), s.sort.block_count());
  // The colouring's condition (cell_sort.hpp): 2 slack + reach <= block_cells.
  EXPECT_LE(2 * s.sort.slack() + 1, bc);
}

// The sort runs in parallel (per-thread slices by block, then per block by cell); its order must be
// that of one stable counting sort by (block, cell) for any thread count, or the results would
// depend on the thread count. Reference: std::stable_sort of the unsorted particles by that key.
TEST(CellSort, TheOrderIsTheStableKeyOrderForAnyThreadCount) {
  GridGeometry g;
  g.h = 0.1;
  g.cells = {20, 12, 9};
  const Grid unsorted_grid(g);
  ParticleStore cloud;
  std::mt19937 rng(11);
  std::uniform_real_distribution<double> u(0.0, 1.0);
  // clustered in a corner and spread thin elsewhere: blocks of very different sizes, empty blocks
  for (int p = 0; p < 5000; ++p) {
    const double s = p % 3 ? 0.3 : 1.0;
    cloud.add(p, Vec3(2.0 * s * u(rng), 1.2 * s * u(rng), 0.9 * u(rng)), Vec3::Zero(), 1.0 + p, 1e-3, 0);
  }
  const int bc = CellSort::block_edge(0, 1, 0);
  auto key = [&](std::size_t p) {
    std::array<int, 6> k{};
    for (int d = 0; d < 3; ++d) {
      const int c = static_cast<int>(std::floor(g.to_grid(d, cloud.x[d][p])));
      k[d] = c / bc;
      k[3 + d] = c % bc;
    }
    return k;
  };
  std::vector<std::size_t> expected(cloud.size());
  std::iota(expected.begin(), expected.end(), 0);
  std::stable_sort(expected.begin(), expected.end(), [&](std::size_t a, std::size_t b) { return key(a) < key(b); });
  const int before = omp_get_max_threads();
  for (int threads : {1, 2, 3, 5}) {
    omp_set_num_threads(threads);
    Grid grid(g);
    ParticleStore particles = cloud;
    CellSort sort(grid, 0, 1);
    sort.sort(particles, grid);
    for (std::size_t p = 0; p < particles.size(); ++p) {
      ASSERT_EQ(particles.id[p], cloud.id[expected[p]]) << threads << " threads, position " << p;
      ASSERT_EQ(particles.mass[p], cloud.mass[expected[p]]);
    }
    // a second sort of the sorted store keeps its order (stable), also after the blocks changed
    const ParticleArray<std::int64_t> ids = particles.id;
    sort.sort(particles, grid);
    EXPECT_EQ(particles.id, ids) << threads << " threads";
    EXPECT_EQ(sort.block_begin(0), 0u);
    EXPECT_EQ(sort.block_end(sort.block_count() - 1), particles.size());
  }
  omp_set_num_threads(before);
}

// ParticleStore::copy_from (the run loop's snapshot, copied in parallel) equals a plain copy.
TEST(ParticleStore, ParallelCopyEqualsACopy) {
  ParticleStore a;
  for (int p = 0; p < 1001; ++p) a.add(p, Vec3(p, -p, 0.5 * p), Vec3(1.0, 2.0, p), 2.0 + p, 1e-3 * p, p % 3);
  a.enable_plastic_state(true);
  for (int p = 0; p < 1001; ++p) a.back_stress[4][p] = 3.0 * p;
  ParticleStore b;
  b.add(7, Vec3(1, 1, 1), Vec3(0, 0, 0), 1.0, 1.0, 0);  // a smaller store is resized
  const int before = omp_get_max_threads();
  omp_set_num_threads(3);
  b.copy_from(a);
  omp_set_num_threads(before);
  EXPECT_EQ(b.size(), a.size());
  EXPECT_EQ(b.id, a.id);
  EXPECT_EQ(b.body, a.body);
  EXPECT_EQ(b.has_plastic_state(), a.has_plastic_state());
  EXPECT_EQ(b.has_back_stress(), a.has_back_stress());
  std::vector<const ParticleArray<double>*> from;
  a.for_each_double_array([&](const char*, const ParticleArray<double>& f) { from.push_back(&f); });
  std::size_t i = 0;
  b.for_each_double_array([&](const char* name, const ParticleArray<double>& f) { EXPECT_EQ(f, *from[i++]) << name; });
}

}  // namespace
}  // namespace cell_sort_test
}  // namespace talus
