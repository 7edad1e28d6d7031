#pragma once
// The one place where scene files are read and validated, and where a scene is written back out
// with every default filled in (the run echoes it into its output folder).
#include "talus/scene/scene.hpp"

#include <nlohmann/json.hpp>

#include <string>

namespace talus {

/// Parse and validate a scene. `source` names the file in error messages.
/// Throws talus::Error (input) naming the key path and the allowed range.
Scene parse_scene(const std::string& text, const std::string& source);
Scene read_scene_file(const std::string& path);

/// An upper bound of the particles the bodies seed (per axis: the body's extent within the grid's
/// extent, over the spacing, + 1), summed.
/// parse_scene refuses scenes above 2^31 particles or 1e9 grid cells (they cannot be allocated).
double particle_count_bound(const Scene& scene);

/// The fully resolved scene; parse_scene(scene_to_json(s).dump()) reproduces s.
nlohmann::json scene_to_json(const Scene& scene);

/// The resolved scene as a run writes it to scene.json, for people and other tools: scene_to_json
/// with grid.size at 12 significant digits (48 cells of 0.0125 give 0.6, not 0.6000000000000001).
/// It parses to the same scene (the cell counts are rounded from size / cell_size), so its hash, of
/// scene_to_json's exact text, is the same: checkpoints of earlier builds still restart from it.
nlohmann::json scene_file_json(const Scene& scene);

}  // namespace talus
