// parallel_sort (core/parallel_sort.hpp): std::sort's result for any thread count when the order is
// a strict total order, including chunk counts that do not divide the length.
#include "talus/core/parallel_sort.hpp"

#include <gtest/gtest.h>
#include <omp.h>

#include <cstdint>
#include <random>

namespace talus {
namespace parallel_sort_test {
namespace {

struct Keyed {
  double key;
  std::int64_t id;  // unique: the tie-break that makes the order total
  bool operator==(const Keyed&) const = default;
};

bool key_then_id(const Keyed& a, const Keyed& b) { return a.key < b.key || (a.key == b.key && a.id < b.id); }

std::vector<Keyed> shuffled(std::size_t n) {
  std::mt19937_64 random(42);
  std::uniform_int_distribution<int> coarse(0, 50);  // many equal keys: the tie-break decides
  std::vector<Keyed> v(n);
  for (std::size_t i = 0; i < n; ++i) v[i] = {0.25 * coarse(random), static_cast<std::int64_t>(i)};
  std::shuffle(v.begin(), v.end(), random);
  return v;
}

TEST(ParallelSort, GivesStdSortsResultForAnyThreadCount) {
  for (const std::size_t n : {std::size_t{0}, std::size_t{1}, std::size_t{1000}, 3 * kParallelSortMinChunk + 7,
                              std::size_t{100003}}) {
    std::vector<Keyed> expected = shuffled(n);
    std::sort(expected.begin(), expected.end(), key_then_id);
    for (const int threads : {1, 2, 3, 4, 8}) {
      omp_set_num_threads(threads);
      std::vector<Keyed> v = shuffled(n);
      parallel_sort(v, key_then_id);
      EXPECT_TRUE(v == expected) << n << " elements, " << threads << " threads";
    }
  }
}

TEST(ParallelSort, CountsItsChunksAndRegions) {
  // the default flume's particles on 16 threads: 8 chunks of at least kParallelSortMinChunk, then 3 levels of merges
  EXPECT_EQ(parallel_sort_chunks(15584, 16), 8);
  EXPECT_EQ(parallel_sort_regions(15584, 16), 4);
  EXPECT_EQ(parallel_sort_chunks(15584, 3), 2);  // a power of two, at most the threads
  EXPECT_EQ(parallel_sort_regions(15584, 1), 0);  // one chunk: std::sort, no region
  EXPECT_EQ(parallel_sort_regions(kParallelSortMinChunk, 64), 0);
}

TEST(ParallelSort, SortsInsideAParallelRegionToo) {
  std::vector<Keyed> expected = shuffled(20000);
  std::sort(expected.begin(), expected.end(), key_then_id);
  std::vector<Keyed> v = shuffled(20000);
  omp_set_num_threads(2);
#pragma omp parallel
  {
#pragma omp single
    parallel_sort(v, key_then_id);  // one thread sorts, serially
  }
  EXPECT_TRUE(v == expected);
}

}  // namespace
}  // namespace parallel_sort_test
}  // namespace talus
