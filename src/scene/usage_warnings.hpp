#pragma once
// What a scene asks for that it likely did not mean, which the reader cannot refuse: a material no
// body uses (a body given the wrong one, say), and checkpoints written at every step.
#include "talus/scene/scene.hpp"

#include <string>
#include <vector>

namespace talus {

/// The warnings, one line each (scene_warnings includes them).
std::vector<std::string> usage_warnings(const Scene& scene);

}  // namespace talus
