#pragma once
// Which instruction set the vectorised kernels run on. One portable binary carries the kernels
// compiled for the baseline x86-64 (scalar: SSE2), AVX2 and AVX-512 by Google Highway and
// picks the best the CPU has at run time; `reference` runs the plain C++ reference path instead of
// the Highway kernels. Every path gives bit-identical results (docs/performance.md, "Vector
// kernels"): the material kernels vectorise ACROSS particles, each lane doing the reference's
// operations in the reference's order; the transfers are the same plain C++ compiled per target
// (the compiler does not reassociate); the build never contracts a*b + c into a fused
// multiply-add (-ffp-contract=off); sums over particles stay in particle order.
// tests/solver/isa_paths_test.cpp checks it.
//
// The choice is global to the process: `talus run|bench --isa NAME` or the environment variable
// TALUS_ISA select it; the default is `auto` (the best path available).
#include <string>
#include <string_view>
#include <vector>

namespace talus {

/// The paths this build and this CPU can run, worst first: "reference", then the Highway targets
/// ("scalar", "avx2", "avx512"; a -DTALUS_NATIVE=ON build has only its CPU's own, e.g. "avx512_dl").
std::vector<std::string> available_isas();

/// Select a path by name ("auto" = the best available). Throws input_error naming `source` (the
/// option or variable the name came from) and the allowed values when `name` is unknown or not
/// available here.
void select_isa(std::string_view name, std::string_view source = "--isa");

/// Select from the environment variable TALUS_ISA when it is set (the same names); otherwise keep
/// the current choice.
void select_isa_from_environment();

/// The path in use ("reference", "avx2", ...).
std::string active_isa();

/// False when the scalar reference path is selected: callers then skip the vector kernels.
bool vector_kernels_enabled();

}  // namespace talus
