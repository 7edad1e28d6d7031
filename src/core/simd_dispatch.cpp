#include "talus/core/simd_dispatch.hpp"

#include "talus/core/error.hpp"

#include <hwy/targets.h>

#include <cctype>
#include <cstdint>
#include <cstdlib>

namespace talus {

namespace {

bool g_vector_kernels = true;
std::int64_t g_forced_target = 0;  // 0: Highway picks the best the CPU supports

void force_target(std::int64_t target) {
  g_forced_target = target;
  hwy::SetSupportedTargetsForTest(target);  // dispatch re-evaluates: it takes this target alone
}

// Highway's name, lower case, with AVX3 (AVX-512 F/VL/DQ/BW) called what users know it as, and
// the portable baseline called "scalar" whichever form this compiler's Highway builds: SCALAR
// (g++ 12) or EMU128 (clang 14), both plain C++ that the compiler turns into SSE2.
std::string isa_name(std::int64_t target) {
  std::string name = hwy::TargetName(target);
  for (char& c : name) c = static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
  if (name.rfind("avx3", 0) == 0) name.replace(0, 4, "avx512");
  if (name == "emu128") name = "scalar";
  return name;
}

// The Highway targets this binary has kernels for and this CPU runs, worst first.
std::vector<std::int64_t> runnable_targets() {
  hwy::SetSupportedTargetsForTest(0);  // the CPU's own set, not the current selection
  const std::vector<std::int64_t> targets = hwy::SupportedAndGeneratedTargets();  // best first
  hwy::SetSupportedTargetsForTest(g_forced_target);
  return {targets.rbegin(), targets.rend()};
}

std::string joined(const std::vector<std::string>& names) {
  std::string s;
  for (const std::string& n : names) s += (s.empty() ? "" : ", ") + n;
  return s;
}

}  // namespace

std::vector<std::string> available_isas() {
  std::vector<std::string> names{"reference"};
  for (std::int64_t t : runnable_targets()) names.push_back(isa_name(t));
  return names;
}

void select_isa(std::string_view name, std::string_view source) {
  if (name == "auto" || name == "reference") {
    force_target(0);
    g_vector_kernels = name == "auto";
    return;
  }
  for (std::int64_t t : runnable_targets())
    if (isa_name(t) == name) {
      force_target(t);
      g_vector_kernels = true;
      return;
    }
  std::vector<std::string> allowed = available_isas();
  allowed.insert(allowed.begin(), "auto");
  throw input_error(std::string(source) + " = '" + std::string(name) + "' is not a vector path this CPU and build run (unknown, or not supported here); allowed: " +
                    joined(allowed));
}

void select_isa_from_environment() {
  if (const char* value = std::getenv("TALUS_ISA"); value && *value) select_isa(value, "TALUS_ISA");
}

std::string active_isa() {
  if (!g_vector_kernels) return "reference";
  const std::vector<std::int64_t> targets = hwy::SupportedAndGeneratedTargets();
  return targets.empty() ? "reference" : isa_name(targets.front());
}

bool vector_kernels_enabled() { return g_vector_kernels; }

}  // namespace talus
