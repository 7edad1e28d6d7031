#pragma once
// Reading one JSON object with full key paths in every error, and a check that no key was left
// unread (a misspelt key is an error, not a silently ignored setting).
#include "talus/core/error.hpp"
#include "talus/core/types.hpp"

#include <fmt/core.h>
#include <nlohmann/json.hpp>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <limits>
#include <optional>
#include <set>
#include <string>
#include <string_view>
#include <vector>

namespace talus::scene_detail {

using Json = nlohmann::json;

inline std::string type_name(const Json& j) { return j.type_name(); }

class ObjectReader {
 public:
  ObjectReader(const Json& object, std::string path) : object_(object), path_(std::move(path)) {
    if (!object_.is_object())
      throw input_error(fmt::format("{} must be an object, got {}", label(), type_name(object_)));
  }

  std::string key_path(const std::string& key) const { return path_.empty() ? key : path_ + "." + key; }
  const std::string& path() const { return path_; }
  bool has(const std::string& key) const { return object_.contains(key); }

  const Json& raw(const std::string& key) {
    used_.insert(key);
    if (!object_.contains(key)) throw input_error(fmt::format("missing required key {}", key_path(key)));
    return object_.at(key);
  }

  /// A finite number in [lo, hi]; `open_lo`/`open_hi` exclude the end point.
  double number(const std::string& key, double lo, double hi, bool open_lo = false, bool open_hi = false) {
    return check_number(raw(key), key_path(key), lo, hi, open_lo, open_hi);
  }
  double number_or(const std::string& key, double fallback, double lo, double hi, bool open_lo = false,
                   bool open_hi = false) {
    if (!has(key)) return fallback;
    return number(key, lo, hi, open_lo, open_hi);
  }

  int integer(const std::string& key, int lo, int hi) {
    const Json& j = raw(key);
    // A whole number written with a point (1000.0, 1e3: what a script's json.dumps of a float
    // gives, and what JSON Schema counts as an integer) is that integer.
    if (j.is_number_float() && std::isfinite(j.get<double>()) && std::trunc(j.get<double>()) == j.get<double>()) {
      const double v = j.get<double>();
      if (v < lo || v > hi)
        throw input_error(fmt::format("{} = {} is outside the allowed range [{}, {}]", key_path(key), j.dump(), lo, hi));
      return static_cast<int>(v);
    }
    if (!j.is_number_integer())
      throw input_error(fmt::format("{} must be an integer in [{}, {}], got {}", key_path(key), lo, hi, j.dump()));
    // A non-negative literal is unsigned to the parser, and past 2^63 - 1 its long long wraps to a
    // negative number: compare it unsigned, and show the number as written.
    const bool past_long_long = j.is_number_unsigned() && j.get<unsigned long long>() > 9223372036854775807ull;
    const long long v = j.get<long long>();
    if (past_long_long || v < lo || v > hi)
      throw input_error(fmt::format("{} = {} is outside the allowed range [{}, {}]", key_path(key), j.dump(), lo, hi));
    return static_cast<int>(v);
  }
  int integer_or(const std::string& key, int fallback, int lo, int hi) {
    return has(key) ? integer(key, lo, hi) : fallback;
  }

  bool boolean_or(const std::string& key, bool fallback) {
    if (!has(key)) return fallback;
    const Json& j = raw(key);
    if (!j.is_boolean()) throw input_error(fmt::format("{} must be true or false, got {}", key_path(key), j.dump()));
    return j.get<bool>();
  }

  std::string string(const std::string& key) {
    const Json& j = raw(key);
    if (!j.is_string()) throw input_error(fmt::format("{} must be a string, got {}", key_path(key), j.dump()));
    return j.get<std::string>();
  }
  std::string string_or(const std::string& key, const std::string& fallback) {
    return has(key) ? string(key) : fallback;
  }

  /// One of a fixed set of words; an empty fallback makes the key required.
  std::string choice(const std::string& key, const std::string& fallback, const std::vector<std::string>& allowed) {
    const std::string value = fallback.empty() ? string(key) : string_or(key, fallback);
    std::string list;
    for (const std::string& a : allowed) {
      if (value == a) return value;
      list += (list.empty() ? "" : ", ") + a;
    }
    throw input_error(fmt::format("{} = \"{}\" is not one of: {}", key_path(key), value, list));
  }

  Vec3 vec3(const std::string& key, double lo = -std::numeric_limits<double>::max(),
            double hi = std::numeric_limits<double>::max(), bool open_lo = false) {
    const Json& j = raw(key);
    if (!j.is_array() || j.size() != 3)
      throw input_error(fmt::format("{} must be an array of 3 numbers, got {}", key_path(key), j.dump()));
    Vec3 v;
    for (int d = 0; d < 3; ++d) v[d] = check_number(j[d], fmt::format("{}[{}]", key_path(key), d), lo, hi, open_lo, false);
    return v;
  }

  ObjectReader object(const std::string& key) { return ObjectReader(raw(key), key_path(key)); }

  /// Refuse a key not in `allowed` before reading any (a misspelt key is named as such, not as the
  /// required key it was meant to be).
  void refuse_unknown(const std::vector<std::string>& allowed) const {
    for (auto it = object_.begin(); it != object_.end(); ++it) {
      if (std::find(allowed.begin(), allowed.end(), it.key()) != allowed.end()) continue;
      std::string known;
      for (const auto& k : allowed) known += (known.empty() ? "" : ", ") + k;
      throw input_error(fmt::format("unknown key {} (allowed here: {})", key_path(it.key()), known));
    }
  }

  /// Every key of the object must have been read; call last.
  void finish() const {
    for (auto it = object_.begin(); it != object_.end(); ++it) {
      if (!used_.count(it.key())) {
        std::string known;
        for (const auto& k : used_) known += (known.empty() ? "" : ", ") + k;
        throw input_error(fmt::format("unknown key {} (keys read here: {})", key_path(it.key()), known));
      }
    }
  }
  /// Mark a key as understood without reading it (e.g. "comment").
  void allow(const std::string& key) { used_.insert(key); }

  /// An end at this magnitude or beyond is unbounded; values beyond it are refused all the same.
  static constexpr double kUnbounded = 1e30;

  /// The interval as messages write it; an end at 1e30 or beyond is unbounded: (0, inf), or with
  /// `as_limits` the limit it still is: (0, 1e+30] (for a value beyond it).
  static std::string interval(double lo, double hi, bool open_lo, bool open_hi, bool as_limits = false) {
    const bool no_lo = lo <= -kUnbounded, no_hi = hi >= kUnbounded;
    const auto end = [as_limits](bool unbounded, double value, double limit, const char* infinity) {
      return !unbounded ? fmt::format("{}", value) : as_limits ? fmt::format("{}", limit) : std::string(infinity);
    };
    return fmt::format("{}{}, {}{}", open_lo || (no_lo && !as_limits) ? "(" : "[", end(no_lo, lo, -kUnbounded, "-inf"),
                       end(no_hi, hi, kUnbounded, "inf"), open_hi || (no_hi && !as_limits) ? ")" : "]");
  }

  static double check_number(const Json& j, const std::string& path, double lo, double hi, bool open_lo, bool open_hi) {
    const auto range = interval(lo, hi, open_lo, open_hi);
    // ("must be a number in (-inf, inf)" for a key with no range: a finite number is what it takes)
    const bool unbounded = lo <= -kUnbounded && hi >= kUnbounded;
    if (!j.is_number())
      throw input_error(fmt::format("{} must be {}, got {}", path, unbounded ? "a finite number" : "a number in " + range,
                                    j.dump()));
    const double v = j.get<double>();
    const bool ok = std::isfinite(v) && (open_lo ? v > lo : v >= lo) && (open_hi ? v < hi : v <= hi);
    // young = 1e308 was refused as "outside (0, inf)": say which limit it broke.
    const bool beyond = std::isfinite(v) && ((v > hi && hi >= kUnbounded) || (v < lo && lo <= -kUnbounded));
    // (with its unbounded ends written as the 1e30 they are: young = 1e31 read as "outside (0, inf)")
    if (!ok && beyond)
      throw input_error(fmt::format("{} = {} is outside the allowed range {} (magnitudes above 1e30 are refused)",
                                    path, v, interval(lo, hi, open_lo, open_hi, true)));
    if (!ok) throw input_error(fmt::format("{} = {} is outside the allowed range {}", path, v, range));
    return v;
  }

 private:
  std::string label() const { return path_.empty() ? "the scene" : path_; }
  const Json& object_;
  std::string path_;
  std::set<std::string> used_;
};

/// Runs a lower layer's check. Its domain error names the value as that layer knows it
/// ("points[1]: ...", "friction_angle = 95 ..."); here the key path goes in front
/// ("grid.terrain.points[1]: ..."), so only the scene layer knows the file's key paths.
template <class Check>
void with_key_path(const std::string& prefix, Check&& check) {
  try {
    check();
  } catch (const Error& e) {
    if (e.kind() != Error::Kind::Input) throw;
    throw input_error(prefix + e.what());
  }
}

/// Why read_text_file found nothing at `path`, for the caller's message: ": it is a folder, not a
/// file", ": no such file", or "" (then the system refused it; `talus check inputs` said only "cannot
/// open scene file inputs").
inline std::string why_unreadable(const std::string& path) {
  std::error_code ec;
  if (std::filesystem::is_directory(path, ec)) return ": it is a folder, not a file";
  if (!std::filesystem::exists(path, ec) && !ec) return ": no such file";
  return "";
}

/// The whole text of a file; nothing when it cannot be opened (the caller names the file's role).
/// The whole file, or nothing when it cannot be read (a folder cannot: reading one gave an empty text
/// and a puzzling "unexpected end of input").
inline std::optional<std::string> read_text_file(const std::string& path) {
  std::error_code ec;
  if (std::filesystem::is_directory(path, ec)) return std::nullopt;
  std::ifstream in(path, std::ios::binary);
  if (!in) return std::nullopt;
  // Read in pieces, stopping at a NUL byte (parse_json refuses it) or past 256 MB: `talus check
  // /dev/zero` read without end.
  constexpr std::size_t kMaxBytes = std::size_t{256} << 20;
  std::string text;
  char piece[1 << 16];
  while (in.read(piece, sizeof piece) || in.gcount() > 0) {
    const std::string_view got(piece, static_cast<std::size_t>(in.gcount()));
    text.append(got);
    if (got.find('\0') != std::string_view::npos) break;
    if (text.size() > kMaxBytes)
      throw input_error(fmt::format("{}: more than 256 MB: not a scene file (a scene is a few kB of JSON)", path));
  }
  return text;
}

/// Refuses a key that an object holds twice. nlohmann's parser keeps the last value, so `"end": 0.1,
/// ..., "end": 5000` would run with 5000 and nothing would say so. The key is named by its full path
/// (`time.end`, `bodies[1].box.min`).
class DuplicateKeyCheck {
 public:
  explicit DuplicateKeyCheck(std::string source) : source_(std::move(source)) {}

  bool operator()(int /*depth*/, Json::parse_event_t event, Json& parsed) {
    using E = Json::parse_event_t;
    switch (event) {
      case E::object_start:
      case E::array_start:
        count_element();
        frames_.push_back(Frame{event == E::object_start, {}, {}, 0});
        break;
      case E::object_end:
      case E::array_end:
        frames_.pop_back();
        break;
      case E::key: {
        Frame& f = frames_.back();
        f.key = parsed.get<std::string>();
        if (!f.keys.insert(f.key).second)
          throw input_error(fmt::format("{}: duplicate key {} (each key may appear once in an object)", source_, path()));
        break;
      }
      case E::value:
        count_element();
        break;
    }
    return true;
  }

 private:
  struct Frame {
    bool object;
    std::set<std::string> keys;
    std::string key;        // an object's key being read
    std::size_t elements;   // an array's elements started so far
  };
  void count_element() {
    if (!frames_.empty() && !frames_.back().object) ++frames_.back().elements;
  }
  std::string path() const {
    std::string p;
    for (const Frame& f : frames_) {
      if (f.object)
        p += (p.empty() ? "" : ".") + f.key;
      else
        p += fmt::format("[{}]", f.elements - 1);
    }
    return p;
  }

  std::string source_;
  std::vector<Frame> frames_;
};

/// Where `number` first stands as a number in the JSON `text` (outside strings, not part of a longer
/// number); npos if nowhere.
inline std::size_t find_number_token(const std::string& text, const std::string& number) {
  const auto numeric = [](char c) { return (c >= '0' && c <= '9') || c == '.' || c == 'e' || c == 'E' || c == '+' || c == '-'; };
  bool in_string = false;
  for (std::size_t i = 0; i < text.size(); ++i) {
    const char c = text[i];
    if (in_string) {
      if (c == '\\') ++i;  // an escaped character, the quote too
      else if (c == '"') in_string = false;
    } else if (c == '"') {
      in_string = true;
    } else if (text.compare(i, number.size(), number) == 0 && (i == 0 || !numeric(text[i - 1])) &&
               (i + number.size() == text.size() || !numeric(text[i + number.size()]))) {
      return i;
    }
  }
  return std::string::npos;
}

/// Parse a whole input file; a syntax error is an input error naming `source`, the line and column.
inline Json parse_json(const std::string& text, const std::string& source) {
  // nlohmann's parser stops at a NUL byte as if the text ended there, so whatever followed passed unread.
  if (const auto nul = text.find('\0'); nul != std::string::npos)
    throw input_error(fmt::format("{}: malformed JSON: a NUL byte at offset {} (not a text file?)", source, nul));
  try {
    return Json::parse(text, DuplicateKeyCheck(source));
  } catch (const Json::exception& e) {
    // nlohmann's message already names the line and column. Not only parse_error: a number that
    // overflows a double (1e999) is an out_of_range error.
    std::string what = e.what();
    const auto bracket = what.find(']');
    if (bracket != std::string::npos) what = what.substr(bracket + 2);
    // The overflow names its number but not where it is: the first number token that spells it
    // (the parser stops at the first overflow; the same text inside a string, a description that
    // quotes "1e999", is not a number).
    const std::string overflow = "number overflow parsing '";
    if (const auto at = what.find(overflow); at != std::string::npos) {
      const std::string number = what.substr(at + overflow.size(), what.find('\'', at + overflow.size()) - at - overflow.size());
      if (const auto where = find_number_token(text, number); !number.empty() && where != std::string::npos) {
        const auto line_start = text.rfind('\n', where);
        const auto line = 1 + std::count(text.begin(), text.begin() + static_cast<std::ptrdiff_t>(where), '\n');
        const auto column = where - (line_start == std::string::npos ? 0 : line_start + 1) + 1;
        what += fmt::format(" at line {}, column {} (beyond the largest double, 1.8e308)", line, column);
      }
    }
    // A comment (`// ...`, `/* ... */`), as in JSONC or a C++ habit: said so, with where notes go.
    if (const auto* parse = dynamic_cast<const Json::parse_error*>(&e); parse && parse->byte >= 1) {
      const std::size_t at = std::min<std::size_t>(parse->byte - 1, text.size());
      const std::size_t slash = text.find('/', at == 0 ? 0 : at - 1);
      if (slash != std::string::npos && slash <= at && slash + 1 < text.size() &&
          (text[slash + 1] == '/' || text[slash + 1] == '*'))
        what += "; JSON has no comments: put notes in a \"comment\" key (any value, ignored)";
    }
    throw input_error(fmt::format("{}: malformed JSON: {}", source, what));
  }
}

}  // namespace talus::scene_detail
