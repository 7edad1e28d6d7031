// LazyArray (core/lazy_array.hpp) reads zero until written and moves its memory; Error
// (core/error.hpp) keeps every message on one line and maps kinds to exit codes.
#include "talus/core/error.hpp"
#include "talus/core/lazy_array.hpp"

#include <gtest/gtest.h>

#include <utility>

namespace talus {
namespace lazy_array_and_error_test {
namespace {

TEST(LazyArray, ReadsZeroUntilWrittenAndMovesItsMemory) {
  LazyArray a(1 << 22);  // 32 MB of address space
  EXPECT_EQ(a.size(), std::size_t(1) << 22);
  EXPECT_EQ(a[0], 0.0);
  EXPECT_EQ(a[(1 << 22) - 1], 0.0);
  a[12345] = 2.5;
  const double* memory = a.data();
  LazyArray b(std::move(a));
  EXPECT_EQ(b.data(), memory);
  EXPECT_EQ(b[12345], 2.5);
  EXPECT_EQ(a.size(), 0u);
  EXPECT_EQ(a.data(), nullptr);
}

TEST(Error, OneLineMessagesAndExitCodes) {
  const Error e = input_error("bodies[0] (\"a\nb\x01\") is bad");
  EXPECT_STREQ(e.what(), "bodies[0] (\"a\\nb\\x01\") is bad");
  EXPECT_EQ(e.exit_code(), 2);
  EXPECT_EQ(instability_error("x").exit_code(), 3);
  EXPECT_EQ(io_error("x").exit_code(), 2);
  // UTF-8 passes whole (μ, φ, a 4-byte sequence); bytes that are not UTF-8 are escaped (a Latin-1
  // scene's bytes reached the terminal raw)
  EXPECT_STREQ(input_error("μ(I) φ = 30° \xf0\x9f\x98\x80").what(), "μ(I) φ = 30° \xf0\x9f\x98\x80");
  EXPECT_STREQ(input_error("last read: '\"elastic\xff\xe9'").what(), "last read: '\"elastic\\xff\\xe9'");
  EXPECT_STREQ(input_error("cut \xce").what(), "cut \\xce");  // a sequence cut short
}

}  // namespace
}  // namespace lazy_array_and_error_test
}  // namespace talus
