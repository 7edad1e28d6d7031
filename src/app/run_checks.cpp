// What `talus run` checks and says before it writes anything, which `talus check` checks and says
// too (run_checks.hpp).
#include "run_checks.hpp"

#include "talus/core/error.hpp"
#include "talus/driver/run_outputs.hpp"
#include "talus/driver/warning.hpp"
#include "talus/io/checkpoint.hpp"
#include "talus/scene/scene_json.hpp"

#include <fmt/core.h>
#include <nlohmann/json.hpp>

#include <unistd.h>

#include <algorithm>
#include <cstdint>
#include <cstdio>
#include <fstream>
#include <functional>
#include <system_error>

namespace talus::app {

namespace {

/// Whether the file at `path` holds the scene as a run writes it to scene.json (as JSON: the layout
/// may differ).
bool holds_resolved_scene(const std::string& path, const Scene& scene) {
  std::ifstream in(path);
  try {
    return nlohmann::json::parse(in) == scene_file_json(scene);
  } catch (const nlohmann::json::exception&) {
    return false;
  }
}

}  // namespace

MachineShare machine_share(const Comm& world, const std::string& restart) {
  MachineShare share;
  share.restart = !restart.empty();
  if (!world.distributed()) return share;
  share.restart_reads_own_part = share.restart && checkpoint_ranks(restart) == world.size();
  char name[256] = {};
  ::gethostname(name, sizeof name - 1);
  // (libstdc++'s string hash has a fixed seed: every rank hashes a name alike)
  const std::uint64_t mine = std::hash<std::string>{}(name);
  const std::vector<std::uint64_t> hosts = world.allgather(mine);
  share.ranks = world.size();
  share.ranks_here = static_cast<int>(std::count(hosts.begin(), hosts.end(), mine));
  share.root_here = hosts[0] == mine;
  return share;
}

std::size_t print_warnings(const Scene& scene, const std::vector<std::string>& more) {
  std::vector<std::string> warnings = scene_warnings(scene);
  warnings.insert(warnings.end(), more.begin(), more.end());
  for (const std::string& w : warnings) warn("{}", w);
  std::fflush(stderr);
  return warnings.size();
}

void require_outputs_spare_inputs(const std::filesystem::path& dir, const std::string& scene_path, const Scene& scene,
                                  const std::string& restart_path, const std::string& record_path) {
  for (const std::filesystem::path& output : run_output_files(dir)) {
    // A resumed run may read the scene.json its first part wrote (`talus run runs/x/scene.json
    // --restart runs/x/checkpoint.h5`): it matches the checkpoint, and is written back unchanged.
    // A scene file of the user's own there (the checkpoint copied next to it) is not: it was replaced.
    const bool resumed_from_its_own_scene = !restart_path.empty() && output.filename() == "scene.json" &&
                                            holds_resolved_scene(scene_path, scene);
    if (same_file(scene_path, output) && !resumed_from_its_own_scene)
      throw input_error(fmt::format("output folder {}: the run would replace the scene file {} by its {}; choose "
                                    "another folder (--out)",
                                    dir.string(), scene_path, output.filename().string()));
    if (!record_path.empty() && same_file(record_path, output))
      throw input_error(fmt::format("--record-work {}: the run writes its {} there; choose another file", record_path,
                                    output.filename().string()));
  }
  // (a frame's name was accepted, and the record replaced that frame of the series)
  if (!record_path.empty() && same_file(std::filesystem::path(record_path).parent_path(), dir / "frames"))
    throw input_error(fmt::format("--record-work {}: the run writes its particle frames in {}; choose another file",
                                  record_path, (dir / "frames").string()));
  if (!record_path.empty() && same_file(record_path, scene_path))
    throw input_error(fmt::format("--record-work {}: that is the scene file; choose another file", record_path));
  if (!record_path.empty() && !restart_path.empty() && same_file(record_path, restart_path))
    throw input_error(fmt::format("--record-work {}: that is the checkpoint to resume from; choose another file",
                                  record_path));
}

void require_no_folder_in_place_of_an_output(const std::filesystem::path& dir) {
  std::error_code ec;
  for (const std::filesystem::path& output : run_output_files(dir))
    if (std::filesystem::is_directory(output, ec))
      throw input_error(fmt::format("output folder {}: {} there is a folder, where the run writes a file of that name; "
                                    "remove it or choose another folder (--out)",
                                    dir.string(), output.filename().string()));
}

}  // namespace talus::app
