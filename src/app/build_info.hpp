#pragma once
// How this talus was built: version, commit, compiler, configuration and the vector paths it runs
// here. `talus --version` prints it, and the bench's JSON records it, so that a figure names the
// build that gave it.
#include <nlohmann/json.hpp>

#include <string>

namespace talus::app {

/// One line: "talus 0.1.0 (commit 8fb6a08..., GNU 12.2.0, Release, portable, MPI; vector paths here:
/// reference, scalar, avx2, avx512)".
std::string build_summary();

/// The same as a JSON object: version, commit, compiler, build_type, native, mpi, vector_paths.
nlohmann::json build_json();

}  // namespace talus::app
