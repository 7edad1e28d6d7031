#pragma once
// Numbers in error messages, written as the user would type them (0.2500001, not 0.25 or
// 0.25000010000000001). std::to_chars keeps talus_dem free of a formatting-library dependency.
#include <charconv>
#include <string>

namespace talus::dem {

/// The shortest text that reads back as the same double.
inline std::string number_text(double value) {
  char buffer[32];
  const auto end = std::to_chars(buffer, buffer + sizeof buffer, value).ptr;
  return {buffer, end};
}

/// Six significant digits, for derived limits such as 1/3.
inline std::string number_text_6(double value) {
  char buffer[32];
  const auto end = std::to_chars(buffer, buffer + sizeof buffer, value, std::chars_format::general, 6).ptr;
  return {buffer, end};
}

}  // namespace talus::dem
