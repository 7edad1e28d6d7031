#include "talus/core/staggered_allocator.hpp"

#include <atomic>
#include <cstdint>
#include <cstring>
#include <new>

namespace talus {

namespace {
constexpr std::size_t kLine = 64, kLinesPerPage = 64, kStaggered = std::size_t{64} << 10;
std::atomic<std::size_t> next_offset{0};
}  // namespace

// The block holds `offset` bytes before the array (offset >= one line); the offset is kept in the
// word just before the array, for the deallocation.
void* staggered_allocate(std::size_t bytes) {
  std::size_t offset = kLine;
  if (bytes >= kStaggered) offset += kLine * (next_offset.fetch_add(1, std::memory_order_relaxed) % kLinesPerPage);
  auto* const block = static_cast<std::byte*>(::operator new(offset + bytes, std::align_val_t{kLine}));
  std::byte* const array = block + offset;
  std::memcpy(array - sizeof(std::size_t), &offset, sizeof(std::size_t));
  return array;
}

void staggered_deallocate(void* p) noexcept {
  if (!p) return;
  auto* const array = static_cast<std::byte*>(p);
  std::size_t offset;
  std::memcpy(&offset, array - sizeof(std::size_t), sizeof(std::size_t));
  ::operator delete(array - offset, std::align_val_t{kLine});
}

}  // namespace talus
