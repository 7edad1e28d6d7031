#pragma once
// Filling the scene's bodies with particles: n x n x n particles per cell at the cell-local points
// (k + 1/2) h / n, keeping those inside the body's box. Each particle carries the volume (h/n)^3 and
// the mass density * volume; ids run from 0 in body order, so they are stable and reproducible.
#include "talus/particles/particle_store.hpp"
#include "talus/scene/scene.hpp"

namespace talus {

/// Seed every body of the scene. Throws input_error for a body that holds no particle.
ParticleStore seed_particles(const Scene& scene);

/// The number of particles seed_particles would make, with the same input errors, without
/// allocating them: a scene's size is known before its memory is (solver/memory_estimate.hpp).
std::size_t count_particles(const Scene& scene);

}  // namespace talus
