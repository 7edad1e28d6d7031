#pragma once
// ParticleScratch: 24 bytes per particle of working memory that the phases of a step borrow one
// at a time.
//
// Three groups of per-particle arrays used to be held for the whole run, each by its own phase:
// the step's displacement (3 doubles: written by G2P, applied after the strain pass, read by the
// CFL guard), the cell sort's keys and orders (4 x uint32) and the permutation's buffer (one field
// at a time). They are never live together: the sort runs at the start of a step, after the last
// displacement has been applied, and the permutation runs at the end of the sort, when only the
// order is still needed. So they share these bytes, 34 B per particle less at the peak
// (docs/performance.md, "Memory").
//
// The memory is 6 planes of `capacity()` four-byte words. An array of 1-, 2- or 4-byte elements
// takes one plane; an array of 8-byte elements two neighbouring planes, from an even one. Every
// plane starts on a 64-byte boundary. A borrower writes an element before it reads it: nothing
// survives from one borrower to the next, and two arrays a borrower holds at once must not share
// a plane. (Each plane() call starts the lifetime of the elements it hands out: reusing the bytes
// for another type is well defined.)
#include <cstddef>
#include <cstdint>
#include <memory>
#include <new>
#include <span>
#include <stdexcept>
#include <type_traits>

namespace talus {

class ParticleScratch {
 public:
  static constexpr int kPlanes = 6;

  /// Room for n particles; keeps the memory when it is large enough (the contents are never kept).
  void reserve(std::size_t n);
  std::size_t capacity() const { return capacity_; }
  /// Bytes held (the memory report).
  std::size_t bytes() const { return capacity_ * kPlanes * 4; }

  /// The first n elements of an array of T in plane `first` (and `first` + 1 for 8-byte T).
  template <class T>
  std::span<T> plane(int first, std::size_t n) {
    static_assert(std::is_trivial_v<T> && (sizeof(T) <= 4 || sizeof(T) == 8));
    constexpr int planes = sizeof(T) == 8 ? 2 : 1;
    if (first < 0 || first + planes > kPlanes || (planes == 2 && first % 2 != 0) || n > capacity_)
      throw std::logic_error("ParticleScratch::plane: no such plane or too few particles reserved");
    std::byte* const start = memory_.get() + static_cast<std::size_t>(first) * capacity_ * 4;
    return {new (start) T[n], n};  // trivial T: no initialisation, no run-time cost
  }

 private:
  struct AlignedDelete {
    void operator()(std::byte* p) const { ::operator delete[](p, std::align_val_t{64}); }
  };
  std::unique_ptr<std::byte[], AlignedDelete> memory_;
  std::size_t capacity_ = 0;
};

}  // namespace talus
