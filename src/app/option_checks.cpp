#include "option_checks.hpp"

#include <unistd.h>

#include <charconv>
#include <cctype>
#include <cmath>
#include <filesystem>

namespace talus::app {

void check_writable_file(const std::string& path, std::string_view option, const std::string& made_folder) {
  namespace fs = std::filesystem;
  std::error_code ec;
  if (fs::is_directory(path, ec)) throw input_error(fmt::format("{} {}: is a folder, not a file", option, path));
  const fs::path parent = fs::path(path).parent_path().empty() ? fs::path(".") : fs::path(path).parent_path();
  // (`talus run s.json --out new --record-work new/work.json` was refused: "the folder new does not exist")
  const auto normal = [](const fs::path& p) {
    std::error_code e;
    fs::path n = fs::weakly_canonical(fs::absolute(p, e), e).lexically_normal();
    return n.has_filename() || !n.has_relative_path() ? n : n.parent_path();  // ("new/" is "new")
  };
  if (!made_folder.empty() && !fs::exists(made_folder, ec) && normal(parent) == normal(made_folder)) return;
  if (!fs::is_directory(parent, ec))
    throw input_error(fs::exists(parent, ec)
                          ? fmt::format("{} {}: cannot write there: {} is a file, not a folder", option, path, parent.string())
                          : fmt::format("{} {}: cannot write there: the folder {} does not exist", option, path,
                                        parent.string()));
  // access() asks the kernel, so that permissions, ACLs and read-only mounts all count.
  if (::access(parent.c_str(), W_OK | X_OK) != 0 || (fs::exists(path, ec) && ::access(path.c_str(), W_OK) != 0))
    throw input_error(fmt::format("{} {}: cannot write there: no write permission", option, path));
}

void check_writable_folder(const std::string& dir, std::string_view what) {
  namespace fs = std::filesystem;
  std::error_code ec;
  fs::path existing = fs::path(dir).lexically_normal();
  while (!existing.empty() && !fs::exists(existing, ec)) {
    // (a link to nothing: "cannot create output folder: File exists", from the first write)
    if (fs::is_symlink(existing, ec))
      throw input_error(fmt::format("{} {}: cannot make it: {} is a link to {}, which does not exist", what, dir,
                                    existing.string(), fs::read_symlink(existing, ec).string()));
    existing = existing.parent_path();
  }
  if (existing.empty()) existing = ".";
  if (!fs::is_directory(existing, ec))
    throw input_error(fmt::format("{} {}: cannot make it: {} is a file, not a folder", what, dir, existing.string()));
  if (::access(existing.c_str(), W_OK | X_OK) != 0)
    throw input_error(fmt::format("{} {}: cannot write there: no write permission in {}", what, dir, existing.string()));
}

std::optional<double> parse_duration(std::string_view text) {
  double total = 0.0;
  std::string_view units = "hms";  // the units still allowed, in order
  std::size_t at = 0;
  while (at < text.size()) {
    std::size_t end = at;
    while (end < text.size() && (std::isdigit(static_cast<unsigned char>(text[end])) || text[end] == '.')) ++end;
    double value = 0.0;
    const auto [stop, error] = std::from_chars(text.data() + at, text.data() + end, value);
    if (end == at || error != std::errc() || stop != text.data() + end) return std::nullopt;
    if (end == text.size() && at == 0) {  // a bare number: seconds
      total = value;
      at = end;
      break;
    }
    const std::size_t unit = end < text.size() ? units.find(text[end]) : std::string_view::npos;
    if (unit == std::string_view::npos) return std::nullopt;
    total += value * (text[end] == 'h' ? 3600.0 : text[end] == 'm' ? 60.0 : 1.0);
    units.remove_prefix(unit + 1);
    at = end + 1;
  }
  if (at == 0 || !std::isfinite(total) || total <= 0.0) return std::nullopt;
  return total;
}

CLI::Option* check_duration(CLI::Option* option) {
  constexpr double kLongestDuration = 8760.0 * 3600.0;
  const std::string name = option->get_name();
  // (a transform, not a check: CLI11 keeps a check's changes to the text from the conversion)
  return option->type_name("DURATION")->transform(CLI::Validator(
      [name](std::string& text) {
        const std::optional<double> seconds = parse_duration(text);
        if (!seconds)
          throw input_error(fmt::format("{} = {} is not a positive duration in h, m and s; give e.g. 3h50m, 90m, 1.5h, 5400s or 5400 (seconds)",
                                        name, text));
        // (no batch job runs a year; past about 2.5 million hours the deadline's nanoseconds overflowed,
        // and the run stopped at its first step)
        if (*seconds > kLongestDuration)
          throw input_error(fmt::format("{} = {} is longer than a year (8760h); give a shorter duration, or leave {} out",
                                        name, text, name));
        text = fmt::format("{}", *seconds);
        return std::string();
      },
      ""));
}

}  // namespace talus::app
