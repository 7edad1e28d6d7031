#pragma once
// Checks of command-line values that every command shares, made while the options are parsed or
// before any work, so that bad input stops at once with one line and exit code 2 (talus::input_error).
#include "talus/core/error.hpp"

#include <CLI/CLI.hpp>
#include <fmt/core.h>

#include <optional>
#include <string>
#include <string_view>
#include <type_traits>

namespace talus::app {

/// The number `text` holds, or the one-line refusal in the scene's words: "--E = abc is not a number",
/// with "; allowed [lo, hi]" when the range is known.
template <typename T>
T option_number(const std::string& name, const std::string& text, const std::string& allowed = {}) {
  T value{};
  if (!CLI::detail::lexical_cast(text, value))
    throw input_error(fmt::format("{} = {} is not {}{}", name, text, std::is_integral_v<T> ? "an integer" : "a number",
                                  allowed.empty() ? "" : "; allowed " + allowed));
  return value;
}

/// Limits a number option to [lo, hi], in place of CLI::Range, which lets NaN through (every comparison
/// with NaN is false) and calls text that is no number "not in range". The message reads as the
/// scene's do: "--mls-radius = nan is outside [0.5, 8]", "--threads = abc is not an integer". It is
/// thrown rather than returned because CLI11 would prefix "--threads: " to a returned one.
/// `shown`, when given, replaces "[lo, hi]" in --help (for an option whose allowed values a later
/// check narrows, as --block-cells's do with the shape).
template <typename T>
CLI::Option* check_range(CLI::Option* option, T lo, T hi, const std::string& shown = {}) {
  static_assert(std::is_arithmetic_v<T>);
  const std::string name = option->get_name(), range = fmt::format("[{}, {}]", lo, hi);
  return option->check(CLI::Validator(
      [name, range, lo, hi](std::string& text) {
        const T value = option_number<T>(name, text, range);
        if (!(value >= lo && value <= hi)) throw input_error(fmt::format("{} = {} is outside {}", name, text, range));
        return std::string();
      },
      shown.empty() ? range : shown));
}

/// Refuses text that is no number, in the words of check_range, for an option whose range a later
/// check gives (dem-springs' --E said CLI11's "Could not convert: --E = abc").
inline CLI::Option* check_number(CLI::Option* option) {
  const std::string name = option->get_name();
  return option->check(CLI::Validator(
      [name](std::string& text) {
        option_number<double>(name, text);
        return std::string();
      },
      ""));
}

/// Refuses an empty value (an unset shell variable, `--restart "$CKPT"`), which would otherwise mean
/// "not given" or "the current folder" without a word. `instead` says what to do, e.g. "leave --out
/// out for runs/<scene name>".
inline CLI::Option* refuse_empty(CLI::Option* option, const std::string& instead) {
  const std::string name = option->get_name();
  return option->check(CLI::Validator(
      [name, instead](std::string& value) {
        if (value.empty()) throw input_error(fmt::format("{} is empty: {}", name, instead));
        return std::string();
      },
      ""));
}

/// Refuses, before any work, an output file that cannot be written: its folder missing or not
/// writable, or the path itself a folder. `option` names the option in the message ("--json").
/// A command that learns this only when it writes has done all its work for nothing.
/// `made_folder`, when given, is a folder the command makes itself before it writes the file (a
/// run's --out, checked with check_writable_folder): a file in it is accepted while it is not there yet.
void check_writable_file(const std::string& path, std::string_view option, const std::string& made_folder = {});

/// Refuses, before any work, an output folder that cannot be made or written: the nearest part of
/// its path that exists must be a writable folder (`--out results.csv/run` or a read-only tree
/// failed only after the solver was built and its banner printed).
void check_writable_folder(const std::string& dir, std::string_view what);

/// A wall-clock duration as a user writes it for a batch job: "3h50m", "90m", "1.5h", "5400s", or a
/// bare number of seconds ("5400"); the units h, m, s in that order, each at most once. Nothing for
/// any other text, or a duration that is not positive and finite.
std::optional<double> parse_duration(std::string_view text);

/// Makes `option` a duration (parse_duration): its value is replaced by the seconds, and anything
/// else is refused with one line naming the option and the forms allowed; so is a duration over a year.
CLI::Option* check_duration(CLI::Option* option);

}  // namespace talus::app
