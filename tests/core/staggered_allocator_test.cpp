// StaggeredAllocator (core/staggered_allocator.hpp): aligned, and large arrays on distinct cache sets.
#include "talus/core/staggered_allocator.hpp"

#include <gtest/gtest.h>

#include <cstdint>
#include <numeric>
#include <set>
#include <vector>

namespace talus {
namespace staggered_allocator_test {
namespace {

std::uintptr_t address(const void* p) { return reinterpret_cast<std::uintptr_t>(p); }

// The property the transfers' speed rests on: arrays of one length allocated one after another start
// at different offsets within a page, so element p of each falls in a different L1 set. With
// std::allocator the 1 MiB arrays below all start at one offset (16 bytes into a page).
TEST(StaggeredAllocator, LargeArraysStartOnDistinctCacheLines) {
  constexpr std::size_t kArrays = 20, kLength = std::size_t{1} << 17;  // 1 MiB of doubles each
  std::vector<ParticleArray<double>> arrays(kArrays);
  std::set<std::uintptr_t> lines_in_page;
  for (auto& a : arrays) {
    a.resize(kLength);
    EXPECT_EQ(address(a.data()) % 64, 0u);
    lines_in_page.insert(address(a.data()) % 4096 / 64);
  }
  EXPECT_EQ(lines_in_page.size(), kArrays);
}

TEST(StaggeredAllocator, SmallArraysAlignedAndEveryArrayKeepsItsValues) {
  ParticleArray<std::int64_t> small(5);
  EXPECT_EQ(address(small.data()) % 64, 0u);
  ParticleArray<double> grown;
  for (int i = 0; i < 100000; ++i) grown.push_back(0.5 * i);  // reallocates through every size
  EXPECT_EQ(address(grown.data()) % 64, 0u);
  ParticleArray<double> copy = grown;
  for (int i = 0; i < 100000; ++i) ASSERT_EQ(copy[i], 0.5 * i) << i;
  copy.clear();
  copy.shrink_to_fit();
  EXPECT_EQ(grown.back(), 0.5 * 99999);
}

}  // namespace
}  // namespace staggered_allocator_test
}  // namespace talus
