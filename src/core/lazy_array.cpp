#include "talus/core/lazy_array.hpp"

#include "talus/core/error.hpp"

#include <sys/mman.h>

#include <string>
#include <utility>

namespace talus {

LazyArray::LazyArray(std::size_t count) : count_(count) {
  if (count == 0) return;
  // Anonymous private mappings read as zero and are backed by memory only once written.
  void* p = mmap(nullptr, count * sizeof(double), PROT_READ | PROT_WRITE,
                 MAP_PRIVATE | MAP_ANONYMOUS | MAP_NORESERVE, -1, 0);
  if (p == MAP_FAILED) {
    throw io_error("cannot reserve " + std::to_string(count * sizeof(double)) +
                   " bytes of address space for the grid");
  }
  data_ = static_cast<double*>(p);
}

LazyArray::~LazyArray() {
  if (data_) munmap(data_, count_ * sizeof(double));
}

LazyArray::LazyArray(LazyArray&& other) noexcept
    : data_(std::exchange(other.data_, nullptr)), count_(std::exchange(other.count_, 0)) {}

LazyArray& LazyArray::operator=(LazyArray&& other) noexcept {
  if (this != &other) {
    if (data_) munmap(data_, count_ * sizeof(double));
    data_ = std::exchange(other.data_, nullptr);
    count_ = std::exchange(other.count_, 0);
  }
  return *this;
}

}  // namespace talus
