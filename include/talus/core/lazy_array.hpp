#pragma once
// A fixed-size array of doubles whose memory the operating system commits only when a page is
// first written. The grid spans the scene's whole bounding box, but a flume is mostly empty: with
// this array, untouched (inactive) regions cost address space, not memory.
#include <cstddef>

namespace talus {

class LazyArray {
 public:
  LazyArray() = default;
  explicit LazyArray(std::size_t count);
  ~LazyArray();
  LazyArray(const LazyArray&) = delete;
  LazyArray& operator=(const LazyArray&) = delete;
  LazyArray(LazyArray&& other) noexcept;
  LazyArray& operator=(LazyArray&& other) noexcept;

  double* data() { return data_; }
  const double* data() const { return data_; }
  double& operator[](std::size_t i) { return data_[i]; }
  double operator[](std::size_t i) const { return data_[i]; }
  std::size_t size() const { return count_; }

 private:
  double* data_ = nullptr;
  std::size_t count_ = 0;
};

}  // namespace talus
