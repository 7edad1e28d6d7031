#pragma once
// StaggeredAllocator: an allocator for the per-particle arrays that starts each large array on its
// own cache-line offset within a 4 KiB page.
//
// Why: the particle fields are ~20 separate arrays of the same length. Large blocks come from mmap,
// page-aligned, so every array started 16 bytes into a page, and element p of each array fell in the
// same L1 set (bits 6-11 of the address: 4 KiB period) and the same L2 set (128 KiB period). A
// transfer pass streams 14-17 of them at once through an 8-way cache set: each line was evicted
// before its 8 particles were used. With arrays at distinct line offsets the P2G of the benches ran
// 3-10% faster, and the split scatter record after it gained 9-17% more (docs/performance.md,
// "Particle arrays on distinct cache sets"). Addresses never enter a result: the bits are unchanged.
#include <cstddef>
#include <vector>

namespace talus {

/// Memory for `bytes` that starts 64-byte aligned; allocations of 64 KiB or more start at a
/// cache-line offset within their page that differs from the previous 63 such allocations'.
void* staggered_allocate(std::size_t bytes);
void staggered_deallocate(void* p) noexcept;

template <class T>
struct StaggeredAllocator {
  using value_type = T;
  StaggeredAllocator() noexcept = default;
  template <class U>
  StaggeredAllocator(const StaggeredAllocator<U>&) noexcept {}
  T* allocate(std::size_t n) { return static_cast<T*>(staggered_allocate(n * sizeof(T))); }
  void deallocate(T* p, std::size_t) noexcept { staggered_deallocate(p); }
  friend bool operator==(const StaggeredAllocator&, const StaggeredAllocator&) noexcept { return true; }
};

/// A per-particle array (ParticleStore's fields).
template <class T>
using ParticleArray = std::vector<T, StaggeredAllocator<T>>;

}  // namespace talus
