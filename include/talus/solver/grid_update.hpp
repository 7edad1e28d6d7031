#pragma once
// The grid phase of a step: node velocities and accelerations, then the boundary conditions.
#include "talus/boundary/walls.hpp"
#include "talus/grid/grid.hpp"

namespace talus {

/// v_i = p_i / m_i, a_i = f_i / m_i + g, v_i^L = v_i + a_i dt (seed 000 eq. 48-49), then the walls.
/// Leaves momentum = v_i, force = v_i^L - v_i (the particle velocity increment), velocity_l = v_i^L.
/// Nodes lighter than `mass_floor` are treated as empty (the small-nodal-mass problem, seed 001 §3).
/// Returns the work dissipated by wall friction (>= 0).
double update_grid(Grid& grid, const Walls& walls, const Vec3& gravity, double dt, double mass_floor);

/// After the MUSL remap: v_i^{k+1} = p_i / m_i with the walls in the contact state of this step's
/// grid update (seed 000 eq. 52, seed 001 eq. 18; Walls::Stage::Remap).
void velocities_from_momentum(Grid& grid, const Walls& walls, double mass_floor);

/// USF / USAVG, before the stress update: the start-of-step nodal velocities v_i = p_i / m_i with
/// the walls' normal velocity removed (Walls::Stage::Start), written to `velocity_l` (momentum is
/// left as it is for update_grid).
void start_velocities(Grid& grid, const Walls& walls, double mass_floor);

}  // namespace talus
