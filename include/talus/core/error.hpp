#pragma once
// One exception type for everything a user can get wrong or a run can hit. The program prints
// what() as one line and exits with exit_code(): 2 for bad input, 3 for a run that went unstable.
#include <cstdio>
#include <stdexcept>
#include <string>
#include <string_view>

namespace talus {

class Error : public std::runtime_error {
 public:
  enum class Kind { Input, Instability, Io };
  Error(Kind kind, const std::string& message) : std::runtime_error(one_line(message)), kind_(kind) {}
  Kind kind() const { return kind_; }
  int exit_code() const { return kind_ == Kind::Instability ? 3 : 2; }
  /// Thrown on every rank of a distributed run at once (Comm::agree), rank 0's naming the rank that
  /// failed: rank 0 alone says it, and the job ends without MPI_Abort, no rank being left in a
  /// collective. (A rank that fails alone names itself and ends the job: run_command.cpp.)
  bool agreed() const { return agreed_; }
  Error& mark_agreed() {
    agreed_ = true;
    return *this;
  }

  /// Control characters (from keys or names in a scene) escaped, so a message is always one line,
  /// and bytes that are not UTF-8 (a scene saved in Latin-1) escaped, so a terminal shows them.
  static std::string one_line(const std::string& text) {
    std::string out;
    out.reserve(text.size());
    auto escape = [&out](unsigned char u) {
      out += "\\x" + std::string(1, "0123456789abcdef"[u >> 4]) + "0123456789abcdef"[u & 15];
    };
    for (std::size_t i = 0; i < text.size(); ++i) {
      const char c = text[i];
      const auto u = static_cast<unsigned char>(c);
      if (c == '\n') out += "\\n";
      else if (u < 0x20 || u == 0x7f) escape(u);
      else if (u < 0x80) out += c;
      else {  // a UTF-8 sequence: a lead byte and 1-3 continuation bytes 10xxxxxx, kept whole
        const std::size_t length = u >= 0xc2 && u <= 0xdf ? 2 : u >= 0xe0 && u <= 0xef ? 3 : u >= 0xf0 && u <= 0xf4 ? 4 : 0;
        bool whole = length > 0 && i + length <= text.size();
        for (std::size_t k = 1; whole && k < length; ++k) whole = (static_cast<unsigned char>(text[i + k]) & 0xc0) == 0x80;
        if (!whole) {
          escape(u);
          continue;
        }
        out.append(text, i, length);
        i += length - 1;
      }
    }
    return out;
  }

 private:
  Kind kind_;
  bool agreed_ = false;
};

/// Bad scene, bad argument, value out of range: message names the key path and allowed range.
inline Error input_error(const std::string& message) { return Error(Error::Kind::Input, message); }
/// NaN, a particle leaving the grid, CFL breach: message names step, particle and quantity.
inline Error instability_error(const std::string& message) {
  return Error(Error::Kind::Instability, message);
}
inline Error io_error(const std::string& message) { return Error(Error::Kind::Io, message); }

/// A value as a message shows it: printf's %g (6 significant digits, no trailing zeros).
inline std::string number_g(double v) {
  char buffer[32];
  std::snprintf(buffer, sizeof buffer, "%g", v);
  return buffer;
}

/// The parameter checks' one message: "<prefix><key> = <value> is out of range; allowed <allowed>".
[[noreturn]] inline void throw_out_of_range(std::string_view prefix, const char* key, double value,
                                            const std::string& allowed) {
  throw input_error(std::string(prefix) + key + " = " + number_g(value) + " is out of range; allowed " + allowed);
}

}  // namespace talus
