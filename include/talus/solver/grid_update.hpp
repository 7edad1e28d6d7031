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

/// Which node velocity fields the mirror reflects.
/// AfterGridUpdateForRemap: as AfterGridUpdate, but the momentum is left alone (the grid update
/// with zero_momentum zeroed it, ghosts included, for the remap's scatter).
enum class GhostFields { AfterGridUpdate, AfterGridUpdateForRemap, Remapped, Start };

// Each node phase below runs, with mirrored walls (fixed and slip: Walls::mirror), between two
// operations on the ghost nodes beyond them:
//   - the fold, before: the mass, momentum and/or force (`fold`: those the scatter just wrote) of
//     each ghost move to its interior image, weighted by the mirror's factors S (Walls::ghosts_of);
//     with the mass goes the ghost's share of the body force, (S - 1) m_ghost g on top of the g the
//     grid update applies to the whole folded mass. The ghost is a slave of the image, so this is
//     the Galerkin equation of the image node in the constrained space. The ghost is left empty (no
//     friction or wall work is counted on it; the node masses still sum to the particle mass);
//   - the mirror, after: the ghost takes the reflection of its image's new velocities.
// All three run in one loop over the active tiles (one stage, no barrier between them: issue 19,
// docs/performance.md "Scaling"). The thread of an image's tile folds its ghosts, does the node
// work on its own nodes, then writes its ghosts' mirrors; the thread of a ghost's tile leaves the
// ghost alone. Each ghost has one image, so no node is touched by two threads. A ghost whose image's
// tile is inactive (no fold reaches it) has the node work of its own tile and then copies the image,
// which nobody writes in the phase; a ghost on an inactive tile is neither folded nor mirrored (no
// particle reaches it and the clear skips it, so it holds only a stale mirror: folding that in gave
// momentum without mass, guards_test.cpp "BlockReboundingOffASlipWallRunsOn"). Every node sees the
// operations of the separate fold, node work and mirror in the same order: the same bits.
// `ghosts`: the walls' ghost nodes, listed per tile (boundary/ghost_map.hpp); without mirrored
// walls the phase is the node work alone, an OwnTile stage.

/// A tile's share of the energy gap's grid terms (EnergyGapTerms, output.energy_gap_terms), per step:
/// with v_mean = (v + v^L) / 2 at each node heavier than the mass floor,
struct TileGapTerms {
  double stress_work = 0.0;         // -dt f . v_mean (f: the scattered force, internal and tractions)
  double wall_work = 0.0;           // -(1/2 m (|v^L|^2 - |v|^2) - dt (f + m g) . v_mean): the walls' share
  double gravity_work = 0.0;        // dt m g . v_mean
  double increment_kinetic = 0.0;   // 1/2 m |v^L - v|^2
};

/// v_i = p_i / m_i, a_i = f_i / m_i + g, v_i^L = v_i + a_i dt (Edo & Matsubara 2015, eq. 48-49), then the walls.
/// Leaves momentum = v_i, force = v_i^L - v_i (the particle velocity increment), velocity_l = v_i^L.
/// Nodes lighter than `mass_floor` are treated as empty (the small-nodal-mass problem, Abe, Johansson & Konagai 2005, §3).
/// `tile_work[t]` receives the work dissipated by wall friction on active tile t (>= 0; sized here);
/// counted_work adds it up.
/// `zero_momentum`: leave momentum = 0 instead of v_i, ready for the remap's scatter (MUSL, USAVG),
/// in the same pass instead of a second one over the active tiles.
/// The ghosts' fold moves `fold`, the mirror reflects v, v^L - v and v^L (not v with zero_momentum).
/// `tile_gap` (null: not counted): per active tile, its TileGapTerms (sized here).
void add_grid_update(TileStages& stages, Grid& grid, const Walls& walls, const GhostMap& ghosts, ScatteredFields fold,
                     const Vec3& gravity, double dt, double mass_floor, bool zero_momentum,
                     std::vector<double>& tile_work, std::vector<TileGapTerms>* tile_gap = nullptr);

/// The wall work of add_grid_update's tiles, added in tile order (the same for any thread count).
/// `counted` (per active tile, TileExchange::counted; empty: all): the tiles whose wall work this
/// rank adds to the total, so that a tile two ranks update is counted once.
double counted_work(const std::vector<double>& tile_work, const std::vector<std::uint8_t>& counted = {});

/// update_grid's stages (without ghost nodes) run on their own (one parallel region); returns the wall work.
double update_grid(Grid& grid, const Walls& walls, const Vec3& gravity, double dt, double mass_floor,
                   const std::vector<std::uint8_t>& counted = {}, bool zero_momentum = false);

/// After the MUSL remap: v_i^{k+1} = p_i / m_i with the walls in the contact state of this step's
/// grid update (Edo & Matsubara 2015, eq. 52, Abe, Johansson & Konagai 2005, eq. 18; Walls::Stage::Remap).
/// The ghosts' fold moves the remapped momentum; the mirror reflects v^{k+1}.
void add_velocities_from_momentum(TileStages& stages, Grid& grid, const Walls& walls, const GhostMap& ghosts,
                                  const Vec3& gravity, double mass_floor);

/// USF / USAVG, before the stress update: the start-of-step nodal velocities v_i = p_i / m_i with
/// the walls' normal velocity removed (Walls::Stage::Start), written to `velocity_l` (momentum is
/// left as it is for the grid update). The ghosts' fold moves mass and momentum; the mirror
/// reflects v_i.
void add_start_velocities(TileStages& stages, Grid& grid, const Walls& walls, const GhostMap& ghosts,
                          const Vec3& gravity, double mass_floor);

}  // namespace talus
