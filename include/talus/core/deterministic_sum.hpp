#pragma once
// Parallel sums whose result does not depend on the thread count: the range is cut into chunks of
// a fixed size, each chunk is summed in order, and the chunk sums are added in order. (An OpenMP
// reduction adds per-thread partial sums, so its last bits change with the thread count.)
#include <array>
#include <cstddef>
#include <vector>

namespace talus {

inline constexpr std::size_t kSumChunk = 4096;

/// Sums K quantities over i in [0, n): term(i, acc) adds particle i's contributions into acc[0..K).
template <std::size_t K, class Term>
std::array<double, K> deterministic_sum(std::size_t n, Term term) {
  const std::size_t chunks = (n + kSumChunk - 1) / kSumChunk;
  std::vector<std::array<double, K>> partial(chunks);
#pragma omp parallel for schedule(static)
  for (std::size_t c = 0; c < chunks; ++c) {
    std::array<double, K> acc{};
    const std::size_t end = (c + 1) * kSumChunk < n ? (c + 1) * kSumChunk : n;
    for (std::size_t i = c * kSumChunk; i < end; ++i) term(i, acc);
    partial[c] = acc;
  }
  std::array<double, K> total{};
  for (const auto& p : partial)
    for (std::size_t k = 0; k < K; ++k) total[k] += p[k];
  return total;
}

}  // namespace talus
