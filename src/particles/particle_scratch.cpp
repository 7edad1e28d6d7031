#include "talus/particles/particle_scratch.hpp"

namespace talus {

void ParticleScratch::reserve(std::size_t n) {
  if (n <= capacity_) return;
  // Planes of a multiple of 16 words: each starts on a 64-byte boundary (a cache line, an AVX-512 load).
  // Whole pages plus 9 lines a plane: the arrays a phase streams together (the displacement's three,
  // the sort's keys) start on different cache sets, not all at one offset within a page
  // (core/staggered_allocator.hpp says why that matters).
  const std::size_t capacity = (n + 1023) / 1024 * 1024 + 144;
  memory_.reset();  // the old contents are never kept: free them before the new block is touched
  capacity_ = 0;
  memory_.reset(static_cast<std::byte*>(::operator new[](capacity * kPlanes * 4, std::align_val_t{64})));
  capacity_ = capacity;
}

}  // namespace talus
