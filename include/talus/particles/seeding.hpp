#pragma once
// Filling the bodies with particles: n x n x n particles per cell at the cell-local points
// (k + 1/2) h / n, keeping those inside the body's box. Each particle carries the volume (h/n)^3 and
// the mass density * volume; ids run from 0 in body order, so they are stable and reproducible.
#include "talus/grid/grid.hpp"
#include "talus/particles/body_spec.hpp"
#include "talus/particles/particle_store.hpp"

#include <cstddef>
#include <functional>
#include <string>
#include <vector>

namespace talus {

/// How an error names body b (default "body b"; the scene gives its key path, "bodies[b]").
using BodyLabel = std::function<std::string(std::size_t body)>;

/// Seed every body on the grid; `material_density[body.material]` is the body's initial density.
/// Throws input_error for a body that holds no particle, naming it by `label`.
/// Which seed points to keep (a distributed run's slab: `keep(position)`); null keeps all. A particle
/// keeps the id it has when every point is kept.
using SeedFilter = std::function<bool(const Vec3& position)>;

ParticleStore seed_particles(const GridGeometry& grid, const std::vector<BodySpec>& bodies,
                             const std::vector<double>& material_density, const BodyLabel& label = {},
                             const SeedFilter& keep = {});

/// What seeding leaves out without an error: a physical body on a terrain grid that reaches below
/// the bed loses the points there (one warning per such body, with the share it loses).
std::vector<std::string> seeding_warnings(const GridGeometry& grid, const std::vector<BodySpec>& bodies,
                                          const BodyLabel& label = {});

/// The seed points per padded cell along x (GridGeometry::cell_of(0, x), clamped to the grid's
/// cells), without making them: how a distributed run cuts its slabs before it seeds.
std::vector<std::int64_t> particles_per_x_cell(const GridGeometry& grid, const std::vector<BodySpec>& bodies,
                                               const BodyLabel& label = {});

/// The number of particles seed_particles would make, with the same input errors, without
/// allocating them: a scene's size is known before its memory is (solver/memory_estimate.hpp).
std::size_t count_particles(const GridGeometry& grid, const std::vector<BodySpec>& bodies, const BodyLabel& label = {});

}  // namespace talus
