// deterministic_sum (core/deterministic_sum.hpp): the same bits for any thread count, and the
// fixed-chunk order it promises.
#include "talus/core/deterministic_sum.hpp"

#include <gtest/gtest.h>
#include <omp.h>

#include <cmath>

namespace talus {
namespace deterministic_sum_test {
namespace {

// Terms of wildly different size, so that any change of summation order changes the last bits.
double term(std::size_t i) { return std::sin(double(i)) * (i % 7 == 0 ? 1e8 : 1e-8); }

TEST(DeterministicSum, SameBitsForOneAndTwoThreadsInTheFixedChunkOrder) {
  const std::size_t n = 5 * kSumChunk + 17;
  auto sum_with = [&](int threads) {
    omp_set_num_threads(threads);
    return deterministic_sum<2>(n, [](std::size_t i, std::array<double, 2>& acc) {
      acc[0] += term(i);
      acc[1] += 1.0;
    });
  };
  const auto one = sum_with(1), two = sum_with(2);
  EXPECT_EQ(one[0], two[0]);
  EXPECT_EQ(one[1], double(n));
  // The promised order: each chunk summed in order, the chunk sums added in order.
  double reference = 0.0;
  for (std::size_t c = 0; c * kSumChunk < n; ++c) {
    double chunk = 0.0;
    for (std::size_t i = c * kSumChunk; i < std::min(n, (c + 1) * kSumChunk); ++i) chunk += term(i);
    reference += chunk;
  }
  EXPECT_EQ(one[0], reference);
}

}  // namespace
}  // namespace deterministic_sum_test
}  // namespace talus
