#pragma once
// The run driver's options for a test that runs a scene through run_scene: into `out_dir`, with no
// progress line, and with the test process's signal handlers left alone.
#include "talus/driver/run_driver.hpp"

#include <filesystem>

namespace talus::test {

inline RunOptions quiet_run_options(const std::filesystem::path& out_dir) {
  RunOptions options;
  options.out_dir = out_dir.string();
  options.progress = false;
  options.handle_signals = false;
  return options;
}

}  // namespace talus::test
