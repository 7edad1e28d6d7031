#pragma once
// The grid phase of a step: node velocities and accelerations, then the boundary conditions.
#include "talus/boundary/walls.hpp"
#include "talus/grid/grid.hpp"

#include <cstdint>
#include <vector>

namespace talus {

/// v_i = p_i / m_i, a_i = f_i / m_i + g, v_i^L = v_i + a_i dt (Edo & Matsubara 2015, eq. 48-49), then the walls.
/// Leaves momentum = v_i, force = v_i^L - v_i (the particle velocity increment), velocity_l = v_i^L.
/// Nodes lighter than `mass_floor` are treated as empty (the small-nodal-mass problem, Abe, Johansson & Konagai 2005, §3).
/// Returns the work dissipated by wall friction (>= 0).
/// `counted` (per active tile, TileExchange::counted; empty: all): the tiles whose wall work this
/// rank adds to the returned total, so that a tile two ranks update is counted once.
/// `zero_momentum`: leave momentum = 0 instead of v_i, ready for the remap's scatter (MUSL, USAVG),
/// in the same pass instead of a second one over the active tiles.
double update_grid(Grid& grid, const Walls& walls, const Vec3& gravity, double dt, double mass_floor,
                   const std::vector<std::uint8_t>& counted = {}, bool zero_momentum = false);

/// After the MUSL remap: v_i^{k+1} = p_i / m_i with the walls in the contact state of this step's
/// grid update (Edo & Matsubara 2015, eq. 52, Abe, Johansson & Konagai 2005, eq. 18; Walls::Stage::Remap).
void velocities_from_momentum(Grid& grid, const Walls& walls, double mass_floor);

/// USF / USAVG, before the stress update: the start-of-step nodal velocities v_i = p_i / m_i with
/// the walls' normal velocity removed (Walls::Stage::Start), written to `velocity_l` (momentum is
/// left as it is for update_grid).
void start_velocities(Grid& grid, const Walls& walls, double mass_floor);

/// Before the velocities are computed: move the mass, momentum and/or force of each mirrored ghost
/// node to its interior image, weighted by the mirror's factors S (Walls::ghosts_of); with the mass
/// goes the ghost's share of the body force, (S - 1) m_ghost g on top of the g that update_grid
/// applies to the whole folded mass. The ghost is a slave of the image, so this is the Galerkin
/// equation of the image node in the constrained space. The ghost is left empty (no friction or
/// wall work is counted on it; the node masses still sum to the particle mass); mirror_ghost_nodes
/// fills its velocities afterwards. Each ghost has one image: race-free and deterministic.
/// `fields`: which of the scattered node fields it moves.
void fold_ghost_nodes(Grid& grid, const Walls& walls, ScatteredFields fields, const Vec3& gravity);

/// Which node velocity fields mirror_ghost_nodes reflects.
/// AfterGridUpdateForRemap: as AfterGridUpdate, but the momentum is left alone (update_grid with
/// zero_momentum zeroed it, ghosts included, for the remap's scatter).
enum class GhostFields { AfterGridUpdate, AfterGridUpdateForRemap, Remapped, Start };

/// Overwrite the ghost nodes beyond fixed and slip walls with the reflection of the interior nodes
/// (Walls::mirror): after update_grid (v, v^L - v, v^L), after the MUSL remap (v^{k+1}) or after
/// start_velocities (v^k). Reads interior nodes only, writes ghost nodes only: race-free.
void mirror_ghost_nodes(Grid& grid, const Walls& walls, GhostFields fields);

}  // namespace talus
