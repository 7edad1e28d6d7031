#pragma once
// The program's warnings: one line each on stderr, "talus: warning: ...", from the run loop and
// its outputs as from the commands (app/).
#include <fmt/core.h>

#include <cstdio>
#include <utility>

namespace talus {

/// Prints "talus: warning: " and the formatted message, and a newline, on stderr, after what
/// stdout holds so far: stdout is flushed first, so that in a log of both (`> log 2>&1`) the
/// warning follows the line it qualifies.
template <class... Args>
void warn(fmt::format_string<Args...> message, Args&&... args) {
  std::fflush(stdout);
  fmt::print(stderr, "talus: warning: {}\n", fmt::format(message, std::forward<Args>(args)...));
}

}  // namespace talus
