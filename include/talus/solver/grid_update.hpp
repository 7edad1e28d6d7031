#pragma once
// The grid phase of a step: node velocities and accelerations, then the boundary conditions.
// Each part is added as stages to a TileStages (grid/tile_stages.hpp), so that the solver runs the
// node work between two scatters in one parallel region.
#include "talus/boundary/ghost_map.hpp"
#include "talus/boundary/walls.hpp"
#include "talus/grid/grid.hpp"
#include "talus/grid/tile_stages.hpp"

#include <cstdint>
#include <vector>

namespace talus {

/// v_i = p_i / m_i, a_i = f_i / m_i + g, v_i^L = v_i + a_i dt (Edo & Matsubara 2015, eq. 48-49), then the walls.
/// Leaves momentum = v_i, force = v_i^L - v_i (the particle velocity increment), velocity_l = v_i^L.
/// Nodes lighter than `mass_floor` are treated as empty (the small-nodal-mass problem, Abe, Johansson & Konagai 2005, §3).
/// `tile_work[t]` receives the work dissipated by wall friction on active tile t (>= 0; sized here);
/// counted_work adds it up.
/// `zero_momentum`: leave momentum = 0 instead of v_i, ready for the remap's scatter (MUSL, USAVG),
/// in the same pass instead of a second one over the active tiles.
void add_grid_update(TileStages& stages, Grid& grid, const Walls& walls, const Vec3& gravity, double dt,
                     double mass_floor, bool zero_momentum, std::vector<double>& tile_work);

/// The wall work of add_grid_update's tiles, added in tile order (the same for any thread count).
/// `counted` (per active tile, TileExchange::counted; empty: all): the tiles whose wall work this
/// rank adds to the total, so that a tile two ranks update is counted once.
double counted_work(const std::vector<double>& tile_work, const std::vector<std::uint8_t>& counted = {});

/// update_grid's stages run on their own (one parallel region); returns the wall work.
double update_grid(Grid& grid, const Walls& walls, const Vec3& gravity, double dt, double mass_floor,
                   const std::vector<std::uint8_t>& counted = {}, bool zero_momentum = false);

/// After the MUSL remap: v_i^{k+1} = p_i / m_i with the walls in the contact state of this step's
/// grid update (Edo & Matsubara 2015, eq. 52, Abe, Johansson & Konagai 2005, eq. 18; Walls::Stage::Remap).
void add_velocities_from_momentum(TileStages& stages, Grid& grid, const Walls& walls, double mass_floor);

/// USF / USAVG, before the stress update: the start-of-step nodal velocities v_i = p_i / m_i with
/// the walls' normal velocity removed (Walls::Stage::Start), written to `velocity_l` (momentum is
/// left as it is for the grid update).
void add_start_velocities(TileStages& stages, Grid& grid, const Walls& walls, double mass_floor);

/// Before the velocities are computed: move the mass, momentum and/or force of each mirrored ghost
/// node to its interior image, weighted by the mirror's factors S (Walls::ghosts_of); with the mass
/// goes the ghost's share of the body force, (S - 1) m_ghost g on top of the g that the grid update
/// applies to the whole folded mass. The ghost is a slave of the image, so this is the Galerkin
/// equation of the image node in the constrained space. The ghost is left empty (no friction or
/// wall work is counted on it; the node masses still sum to the particle mass); the mirror fills
/// its velocities afterwards. Each ghost has one image: race-free and deterministic.
/// `fields`: which of the scattered node fields it moves. No stage without mirrored walls.
/// `ghosts`: the walls' ghost nodes, listed per tile (boundary/ghost_map.hpp).
void add_fold_ghost_nodes(TileStages& stages, Grid& grid, const GhostMap& ghosts, ScatteredFields fields,
                          const Vec3& gravity);

/// Which node velocity fields the mirror reflects.
/// AfterGridUpdateForRemap: as AfterGridUpdate, but the momentum is left alone (the grid update
/// with zero_momentum zeroed it, ghosts included, for the remap's scatter).
enum class GhostFields { AfterGridUpdate, AfterGridUpdateForRemap, Remapped, Start };

/// Overwrite the ghost nodes beyond fixed and slip walls with the reflection of the interior nodes
/// (Walls::mirror): after the grid update (v, v^L - v, v^L), after the MUSL remap (v^{k+1}) or
/// after the start velocities (v^k). Reads interior nodes only, writes ghost nodes only: race-free.
/// No stage without mirrored walls.
void add_mirror_ghost_nodes(TileStages& stages, Grid& grid, const GhostMap& ghosts, GhostFields fields);

}  // namespace talus
