#pragma once
// What `talus run` checks and says before it writes anything, which `talus check` checks and says
// too (each subcommand in its own file: run_command.cpp, check_command.cpp).
#include "talus/core/comm.hpp"
#include "talus/scene/scene.hpp"
#include "talus/solver/memory_estimate.hpp"

#include <cstddef>
#include <filesystem>
#include <string>
#include <vector>

namespace talus::app {

/// How this run's ranks sit on the machines, for the memory check: under mpirun the ranks on this
/// host, known by their host names (a check of the whole scene against each host's memory refused
/// any scene larger than one node, however many nodes ran it). `restart`: the checkpoint a run
/// resumes from (empty: none). Collective under mpirun.
MachineShare machine_share(const Comm& world, const std::string& restart);

/// The scene's warnings and `more` (the disk's), one line each on stderr, after what stdout holds
/// so far; returns how many.
std::size_t print_warnings(const Scene& scene, const std::vector<std::string>& more = {});

/// Refuses a run that would replace one of its own inputs, before anything is written: the scene
/// file among the files the run writes or clears in its folder (`talus run proj/scene.json --out proj` replaced the user's scene by the resolved one),
/// or the work record written over the scene, the checkpoint, one of those files or a frame.
void require_outputs_spare_inputs(const std::filesystem::path& dir, const std::string& scene_path, const Scene& scene,
                                  const std::string& restart_path, const std::string& record_path);

/// Refuses a folder in the output folder with the name of a file the run writes (particles.pvd/):
/// an empty one was deleted without a word, and one with files in it stopped the run at its first
/// write of that file, with frames already written and a temporary file left behind.
void require_no_folder_in_place_of_an_output(const std::filesystem::path& dir);

}  // namespace talus::app
