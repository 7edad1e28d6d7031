// ParticleScratch (particles/particle_scratch.hpp): the planes the sort, the permutation and the
// step's displacement borrow in turn must be aligned and disjoint, and the permutation and the
// sort through a borrowed scratch must give what they gave with arrays of their own.
#include "talus/particles/cell_sort.hpp"
#include "talus/particles/particle_scratch.hpp"
#include "talus/particles/particle_store.hpp"

#include <gtest/gtest.h>

#include <cstdint>
#include <random>
#include <set>
#include <stdexcept>
#include <vector>

namespace talus {
namespace particle_scratch_test {
namespace {

TEST(ParticleScratch, PlanesAreAlignedAndDisjoint) {
  ParticleScratch scratch;
  const std::size_t n = 1001;  // not a multiple of the 16-word rounding
  scratch.reserve(n);
  ASSERT_GE(scratch.capacity(), n);
  EXPECT_EQ(scratch.bytes(), scratch.capacity() * ParticleScratch::kPlanes * 4);
  for (int k = 0; k < ParticleScratch::kPlanes; ++k) {
    const auto plane = scratch.plane<std::uint32_t>(k, n);
    EXPECT_EQ(reinterpret_cast<std::uintptr_t>(plane.data()) % 64, 0u) << "plane " << k;
    for (std::size_t i = 0; i < n; ++i) plane[i] = static_cast<std::uint32_t>(k * 1000003 + i);
  }
  for (int k = 0; k < ParticleScratch::kPlanes; ++k) {
    const auto plane = scratch.plane<std::uint32_t>(k, n);
    for (std::size_t i = 0; i < n; ++i) ASSERT_EQ(plane[i], static_cast<std::uint32_t>(k * 1000003 + i)) << "plane " << k;
  }
  // the three double arrays (the displacement) do not overlap either
  for (int k = 0; k < ParticleScratch::kPlanes; k += 2) {
    const auto d = scratch.plane<double>(k, n);
    for (std::size_t i = 0; i < n; ++i) d[i] = k + 1e-3 * static_cast<double>(i);
  }
  for (int k = 0; k < ParticleScratch::kPlanes; k += 2) {
    const auto d = scratch.plane<double>(k, n);
    for (std::size_t i = 0; i < n; ++i) ASSERT_EQ(d[i], k + 1e-3 * static_cast<double>(i));
  }
}

// The arrays a phase streams together start on different cache sets, also for a particle count
// whose planes would otherwise be whole pages (2^20 particles: 4 MiB planes).
TEST(ParticleScratch, PlanesStartOnDistinctCacheLinesOfAPage) {
  for (const std::size_t n : {std::size_t{1} << 20, std::size_t{1000000}, std::size_t{15584}}) {
    ParticleScratch scratch;
    scratch.reserve(n);
    std::set<std::uintptr_t> lines;
    for (int k = 0; k < ParticleScratch::kPlanes; ++k)
      lines.insert(reinterpret_cast<std::uintptr_t>(scratch.plane<std::uint32_t>(k, n).data()) % 4096 / 64);
    EXPECT_EQ(lines.size(), static_cast<std::size_t>(ParticleScratch::kPlanes)) << n << " particles";
  }
}

TEST(ParticleScratch, RefusesPlanesItDoesNotHave) {
  ParticleScratch scratch;
  scratch.reserve(100);
  EXPECT_THROW(scratch.plane<double>(1, 10), std::logic_error);  // 8-byte arrays start on an even plane
  EXPECT_THROW(scratch.plane<std::uint32_t>(ParticleScratch::kPlanes, 10), std::logic_error);
  EXPECT_THROW(scratch.plane<std::uint32_t>(0, scratch.capacity() + 1), std::logic_error);
  const std::size_t capacity = scratch.capacity();
  scratch.reserve(10);  // smaller: keeps what it has
  EXPECT_EQ(scratch.capacity(), capacity);
}

ParticleStore random_store(std::size_t n, unsigned seed) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> u(0.0, 1.0);
  ParticleStore P;
  for (std::size_t p = 0; p < n; ++p)
    P.add(static_cast<std::int64_t>(p), Vec3(2.0 * u(rng), 1.2 * u(rng), 0.9 * u(rng)), Vec3(u(rng), u(rng), u(rng)),
          1.0 + u(rng), 1e-3 * (1.0 + u(rng)), static_cast<std::uint16_t>(p % 3));
  P.enable_plastic_state(true);
  P.enable_domain_state();
  P.for_each_double_array([&](const char* name, ParticleArray<double>& a) {
    if (name[0] == 'x') return;  // the positions stay in the grid
    for (double& value : a) value += u(rng);
  });
  return P;
}

TEST(ParticleScratch, PermuteThroughTheScratchGathersEveryField) {
  const ParticleStore before = random_store(777, 3);
  std::vector<std::uint32_t> order;  // a subset, reversed and strided: the outflow's kind of order
  for (std::size_t p = before.size(); p-- > 0;)
    if (p % 3 != 1) order.push_back(static_cast<std::uint32_t>(p));
  ParticleStore after = before;
  ParticleScratch scratch;
  scratch.reserve(before.size());
  after.permute(order, scratch, 4);
  ASSERT_EQ(after.size(), order.size());
  for (std::size_t i = 0; i < order.size(); ++i) {
    ASSERT_EQ(after.id[i], before.id[order[i]]);
    ASSERT_EQ(after.body[i], before.body[order[i]]);
  }
  std::vector<const ParticleArray<double>*> old_arrays;
  before.for_each_double_array([&](const char*, const ParticleArray<double>& a) { old_arrays.push_back(&a); });
  std::size_t array = 0, checked = 0;
  after.for_each_double_array([&](const char* name, const ParticleArray<double>& a) {
    const ParticleArray<double>& old = *old_arrays[array++];
    if (old.empty()) return;
    ASSERT_EQ(a.size(), order.size()) << name;
    for (std::size_t i = 0; i < order.size(); ++i) ASSERT_EQ(a[i], old[order[i]]) << name << " " << i;
    ++checked;
  });
  EXPECT_EQ(checked, 3 + 3 + 3 + 6 + 6 + 1 + 6 + 3u);  // x v mass volume volume0 stress strain plastic back domain
}

TEST(ParticleScratch, ASortThroughABorrowedScratchMatchesOneWithItsOwn) {
  GridGeometry g;
  g.h = 0.1;
  g.cells = {20, 12, 9};
  Grid grid_own(g), grid_borrowed(g);
  ParticleStore own = random_store(3000, 11), borrowed = own;
  CellSort sort_own(grid_own, 0, 1), sort_borrowed(grid_borrowed, 0, 1);
  sort_own.sort(own, grid_own);
  ParticleScratch scratch;
  scratch.reserve(10);  // too small: the sort makes room
  sort_borrowed.sort(borrowed, grid_borrowed, scratch);
  EXPECT_GE(scratch.capacity(), borrowed.size());
  // a second sort after another borrower left its bytes everywhere (as G2P's displacement does)
  for (int k = 0; k < ParticleScratch::kPlanes; ++k)
    for (std::uint32_t& w : scratch.plane<std::uint32_t>(k, scratch.capacity())) w = 0xdeadbeefu;
  for (std::size_t p = 0; p < borrowed.size(); ++p) borrowed.x[0][p] = 1.999 - borrowed.x[0][p];  // mirrored: a new order
  for (std::size_t p = 0; p < own.size(); ++p) own.x[0][p] = 1.999 - own.x[0][p];
  sort_borrowed.sort(borrowed, grid_borrowed, scratch);
  sort_own.sort(own, grid_own);
  EXPECT_EQ(borrowed.id, own.id);
  EXPECT_EQ(borrowed.x, own.x);
  EXPECT_EQ(borrowed.domain, own.domain);
  ASSERT_EQ(sort_borrowed.block_count(), sort_own.block_count());
  EXPECT_EQ(sort_borrowed.cell_start(), sort_own.cell_start());
}

}  // namespace
}  // namespace particle_scratch_test
}  // namespace talus
