#pragma once
// The field check of stability_guards.hpp with one more finding, short of an instability: a particle
// of a granular body without the separation rule that has dilated past kDilationWarningRatio times its
// seeded volume (docs/reliability.md, "Instability guards"). A header of its own: stability_guards.hpp
// is read by the solver's and the checkpoint's headers, and this is the run driver's alone.
#include "talus/particles/particle_store.hpp"
#include "talus/scene/scene.hpp"

#include <cstdint>
#include <string>

namespace talus {

/// V/V0 past which a particle of a granular body (Drucker-Prager, μ(I)) without the separation rule
/// (separation_volume_ratio = 0) is warned about: nothing bounds its dilation then. A hunt's column with
/// psi = 30 and the rule off reached V/V0 = 274 (density 5.8 kg/m^3) by 0.4 s while its time step fell
/// tenfold, without a word; seeded sand loosened tenfold is no continuum.
inline constexpr double kDilationWarningRatio = 10.0;

/// check_particle_fields (throws as it does) in the same single pass over the particles, which also
/// compares each volume with kDilationWarningRatio times its seeded one where the body has no separation
/// rule. Returns the first such particle as a warning's line (step, particle, V/V0, density, the key),
/// or an empty string.
std::string check_particle_fields_and_dilation(const ParticleStore& particles, const Scene& scene, std::int64_t step,
                                               double time);

}  // namespace talus
