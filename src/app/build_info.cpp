#include "build_info.hpp"

#include "talus/app/commit.hpp"
#include "talus/core/simd_dispatch.hpp"
#include "talus/core/version.hpp"

#include <fmt/core.h>

#include <vector>

namespace talus::app {

std::string build_summary() {
  std::string paths;
  for (const std::string& name : available_isas()) paths += (paths.empty() ? "" : ", ") + name;
  return fmt::format("talus {} (commit {}, {}, {}, {}, {}; vector paths here: {})", kVersion, kCommit, kCompiler,
                     kBuildType, kNativeBuild ? "native (this CPU only)" : "portable",
                     kMpiBuild ? "MPI" : "no MPI", paths);
}

nlohmann::json build_json() {
  return {{"version", kVersion},     {"commit", kCommit}, {"compiler", kCompiler},
          {"build_type", kBuildType}, {"native", kNativeBuild}, {"mpi", kMpiBuild},
          {"vector_paths", available_isas()}};
}

}  // namespace talus::app
