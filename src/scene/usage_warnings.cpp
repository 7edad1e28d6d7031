#include "usage_warnings.hpp"

#include <fmt/core.h>

namespace talus {

std::vector<std::string> usage_warnings(const Scene& scene) {
  std::vector<std::string> warnings;
  // A material no body uses: defined for nothing, or the body meant to use it names another.
  for (std::size_t m = 0; m < scene.materials.size(); ++m) {
    bool used = false;
    for (const BodySpec& body : scene.bodies) used = used || body.material == static_cast<int>(m);
    if (!used)
      warnings.push_back(fmt::format("materials.{} is used by no body: is a body's \"material\" meant to name it?",
                                     scene.materials[m].name));
  }
  // A checkpoint (about 200 B a particle, written whole) due more often than a step is written at
  // every step: the run spends its time writing the same file.
  const double interval = scene.output.checkpoint_interval, dt = scene.initial_time_step();
  if (interval > 0.0 && interval < dt)
    warnings.push_back(fmt::format(
        "output.checkpoint_interval = {} s is shorter than the time step ({:.3g} s at the start): a checkpoint is "
        "written at every step, the whole state each time; an interval of many steps "
        "keeps the cost small",
        interval, dt));
  return warnings;
}

}  // namespace talus
