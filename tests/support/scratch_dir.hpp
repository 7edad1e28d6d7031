#pragma once
// A test's scratch folder: fresh and empty when made, removed with everything in it when the
// object goes. Header-only and free of the talus libraries, so that every test group (and the
// sanitizer build, which does not build the talus program) can use it.
#include <unistd.h>

#include <filesystem>
#include <string>
#include <system_error>
#include <utility>

namespace talus::test {

class ScratchDir {
 public:
  /// <temporary directory>/talus_<label>_<pid>, emptied first if an earlier process of that id left
  /// it. The process id keeps the parallel ctest processes apart: the label must tell apart the
  /// folders of one process (and carry anything else that must, such as an MPI world's size).
  explicit ScratchDir(const std::string& label)
      : path_(std::filesystem::temp_directory_path() / ("talus_" + label + "_" + std::to_string(::getpid()))) {
    std::filesystem::remove_all(path_);
    std::filesystem::create_directories(path_);
  }
  /// Removes the folder; a failure to remove it is ignored (a test's end must not throw).
  ~ScratchDir() {
    if (path_.empty()) return;
    std::error_code ignored;
    std::filesystem::remove_all(path_, ignored);
  }
  ScratchDir(ScratchDir&& other) noexcept : path_(std::exchange(other.path_, {})) {}
  ScratchDir(const ScratchDir&) = delete;
  ScratchDir& operator=(const ScratchDir&) = delete;
  ScratchDir& operator=(ScratchDir&&) = delete;

  const std::filesystem::path& path() const { return path_; }
  std::filesystem::path operator/(const std::filesystem::path& name) const { return path_ / name; }
  /// So that the folder passes where a path is taken.
  operator const std::filesystem::path&() const { return path_; }

 private:
  std::filesystem::path path_;
};

}  // namespace talus::test
