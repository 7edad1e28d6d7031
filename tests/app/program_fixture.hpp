#pragma once
// A test that runs the talus program itself: a fresh temporary folder per test, the program run with
// its standard output and error captured separately, and small files written into the folder.
#include "../support/scratch_dir.hpp"

#include <gtest/gtest.h>

#include <sys/wait.h>
#include <unistd.h>

#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>

namespace talus::test {

namespace fs = std::filesystem;

struct ProgramResult {
  int exit_code = -1;
  std::string out, err;
};

inline std::string slurp(const fs::path& p) {
  std::ifstream in(p);
  std::stringstream s;
  s << in.rdbuf();
  return s.str();
}

/// The name of the running test, for its folder: <suite>_<test>.
inline std::string current_test_label() {
  const auto* info = ::testing::UnitTest::GetInstance()->current_test_info();
  return std::string(info->test_suite_name()) + "_" + info->name();
}

class ProgramTest : public ::testing::Test {
 protected:

  /// Run `talus ARGS` (ARGS as a shell would split them).
  ProgramResult run(const std::string& args) const {
    const fs::path out = dir_ / "stdout.txt", err = dir_ / "stderr.txt";
    const std::string command =
        std::string("\"") + TALUS_BINARY + "\" " + args + " > \"" + out.string() + "\" 2> \"" + err.string() + "\"";
    const int status = std::system(command.c_str());
    ProgramResult r;
    r.exit_code = WIFEXITED(status) ? WEXITSTATUS(status) : -1;
    r.out = slurp(out);
    r.err = slurp(err);
    return r;
  }

  /// Write `text` to the file `name` in the test's folder.
  fs::path write(const std::string& name, const std::string& text) const {
    const fs::path p = dir_ / name;
    std::ofstream(p) << text;
    return p;
  }

  ScratchDir scratch_{current_test_label()};
  fs::path dir_ = scratch_.path();
};

}  // namespace talus::test
