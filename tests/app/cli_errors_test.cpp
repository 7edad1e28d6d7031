// Command-line mistakes as a user makes them: each is one line on stderr starting "talus: error: ",
// naming the option (or word) and what is allowed, exit code 2, before any work and with no output.
#include "program_fixture.hpp"

#include <gtest/gtest.h>

#include <unistd.h>

#include <algorithm>
#include <filesystem>
#include <string>

namespace cli_errors_test {
namespace {

namespace fs = std::filesystem;

using talus::test::ProgramResult;

class CliErrors : public talus::test::ProgramTest {};

/// Exit code 2, nothing on stdout (no work done), exactly `line` on stderr.
void expect_error_line(const ProgramResult& r, const std::string& line) {
  EXPECT_EQ(r.exit_code, 2) << line;
  EXPECT_EQ(r.out, "");
  EXPECT_EQ(r.err, "talus: error: " + line + "\n");
}

// CLI::Range lets NaN through (NaN compares false), and bench wrote it into its scene JSON, whose
// parser then failed with an internal message; text that is no number was "not in range".
TEST_F(CliErrors, BenchNumberOptionsRefuseNonFiniteValuesAndNonNumbersNamingTheRange) {
  expect_error_line(run("bench --mls linear --mls-radius nan"), "--mls-radius = nan is outside [0.5, 8]");
  expect_error_line(run("bench --mls linear --mls-radius inf"), "--mls-radius = inf is outside [0.5, 8]");
  expect_error_line(run("bench --mls linear --mls-radius -inf"), "--mls-radius = -inf is outside [0.5, 8]");
  expect_error_line(run("bench --mls-radius 9"), "--mls-radius = 9 is outside [0.5, 8]");
  expect_error_line(run("bench --threads abc"), "--threads = abc is not an integer; allowed [1, 4096]");
  expect_error_line(run("bench --steps 0"), "--steps = 0 is outside [1, 1000000]");
  expect_error_line(run("bench --particles 1e6"), "--particles = 1e6 is not an integer; allowed [1000, 100000000]");
}

}  // namespace
}  // namespace cli_errors_test
