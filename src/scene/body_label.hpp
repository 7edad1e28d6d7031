#pragma once
// How seeding names a body in its errors and warnings (scene.cpp, scene_warnings.cpp).
#include "talus/particles/seeding.hpp"
#include "talus/scene/scene.hpp"

namespace talus {

/// A body's key path: bodies[i], or bodies[i].prism for a prism.
BodyLabel body_label(const Scene& scene);

}  // namespace talus
