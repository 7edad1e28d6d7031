#include "option_checks.hpp"

#include <unistd.h>

#include <filesystem>

namespace talus::app {

void check_writable_file(const std::string& path, std::string_view option) {
  namespace fs = std::filesystem;
  std::error_code ec;
  if (fs::is_directory(path, ec)) throw input_error(fmt::format("{} {}: is a folder, not a file", option, path));
  const fs::path parent = fs::path(path).parent_path().empty() ? fs::path(".") : fs::path(path).parent_path();
  if (!fs::is_directory(parent, ec))
    throw input_error(fmt::format("{} {}: cannot write there: the folder {} does not exist", option, path, parent.string()));
  // access() asks the kernel, so that permissions, ACLs and read-only mounts all count.
  if (::access(parent.c_str(), W_OK | X_OK) != 0 || (fs::exists(path, ec) && ::access(path.c_str(), W_OK) != 0))
    throw input_error(fmt::format("{} {}: cannot write there: no write permission", option, path));
}

void check_writable_folder(const std::string& dir, std::string_view what) {
  namespace fs = std::filesystem;
  std::error_code ec;
  fs::path existing = fs::path(dir).lexically_normal();
  while (!existing.empty() && !fs::exists(existing, ec)) existing = existing.parent_path();
  if (existing.empty()) existing = ".";
  if (!fs::is_directory(existing, ec))
    throw input_error(fmt::format("{} {}: cannot make it: {} is a file, not a folder", what, dir, existing.string()));
  if (::access(existing.c_str(), W_OK | X_OK) != 0)
    throw input_error(fmt::format("{} {}: cannot write there: no write permission in {}", what, dir, existing.string()));
}

}  // namespace talus::app
