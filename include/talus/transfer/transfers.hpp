#pragma once
// The particle <-> grid transfers of one step. Each is a template over the shape function and the
// terrain type, so the inner loops have compile-time extents: the kernels are in transfer_kernels-inl.h,
// compiled per shape and instruction set in transfers_<shape>.cpp; transfers.cpp picks the
// instruction set's entry from a table of function pointers.
//
//  scatter_to_grid    P2G: nodal mass, momentum and internal force (Edo & Matsubara 2015, eq. 47-49), as 8
//                     colour passes over blocks: no atomics, same order for any thread count; or, with
//                     BlockBuffers, one pass into each block's own box and a sum of the boxes.
//  gather_from_grid   G2P: v_p += sum N_i (v_i^L - v_i), x_p += dt sum N_i v_i^L (Edo & Matsubara 2015, eq. 50-51),
//                     parallel over blocks (pure gather); with the MUSL remap folded in, the new
//                     momentum is scattered right after each particle's gather, in colour passes.
//  strain_increments  d_eps_p = dt/2 sum (grad N_i (x) v_i + transpose) and the spin increment
//                     (Edo & Matsubara 2015, eq. 33), for a range of particles into a small buffer.
#include "talus/grid/grid.hpp"
#include "talus/particles/cell_sort.hpp"
#include "talus/particles/particle_store.hpp"
#include "talus/transfer/block_buffers.hpp"
#include "talus/transfer/colour_pass_timing.hpp"

#include <array>
#include <cstddef>
#include <limits>
#include <span>
#include <vector>

namespace talus {

enum class ScatterFields {
  MassMomentumForce,  // the full P2G of a step
  Momentum,           // the MUSL remap: momentum only (nodal mass is unchanged)
  MassMomentum,       // USF / USAVG: the start-of-step nodal velocities, before the stress update
  Force,              // USF / USAVG: the internal force of the updated stress
};

template <class Shape, class Terrain>
void scatter_to_grid(const ParticleStore& particles, const CellSort& sort, Grid& grid, ScatterFields fields,
                     ColourPassTiming* timing = nullptr,  // timing: the work recorder's, null normally
                     BlockBuffers* buffers = nullptr);    // buffers: one pass into the blocks' boxes, which
                                                          // the caller adds with buffers->add_sum_stage()

struct GatherResult {
  bool needs_sort = false;          // some particle drifted beyond its block's slack
  long long nonfinite = -1;         // index of a particle whose velocity became NaN/Inf, or -1
  long long outside = -1;           // index of a particle that left the grid, or -1
  bool large_displacement = false;  // some displacement exceeded GatherOptions::max_displacement
  bool crosses_open_face = false;   // some particle will be beyond an open face after the move
  double max_displacement2 = 0.0;   // the largest |displacement|^2 of the pass (m^2): the drift
                                    // from the sorted cells that the MLS neighbour search allows for
};

/// What G2P does besides the gather, and the limits it flags on the way (the CFL guard and the
/// outflow faces read the displacement and the new positions the pass computes anyway, so their own
/// scans of every particle run only in a step that a flag names).
struct GatherOptions {
  double dt = 0.0;
  /// beta in [0, 1]: v_p = (1 - beta) (v_p + sum N (v^L - v)) + beta sum N v^L (0 = FLIP,
  /// Edo & Matsubara 2015, eq. 50; 1 = PIC). With beta > 0 the kinetic energy the blend removes is written per
  /// sort block into `block_damping` (sized to the block count), for a thread-independent sum.
  double pic_fraction = 0.0;
  /// MUSL, USAVG: also scatter the new particle momentum m_p v_p into grid.momentum (cleared by the
  /// caller), the remap of Edo & Matsubara 2015, eq. 52, in the same pass with the same weights; the nodal sums
  /// are those of scatter_to_grid(..., ScatterFields::Momentum), in the same order.
  bool remap = false;
  /// Non-null (output.energy_gap_terms): per sort block (sized to the block count), this step's
  /// sum_p 1/2 m_p |sum_I N_Ip (v^L - v)_I|^2, the kinetic energy of the FLIP increments (before any
  /// PIC share), for EnergyGapTerms::transfer_loss.
  std::vector<double>* block_increment_kinetic = nullptr;
  double max_displacement = std::numeric_limits<double>::infinity();  // [m], flags |dx_p| above it
  /// Faces where particles leave (open walls): lo/hi bounds per axis, in (x, y, w).
  std::array<std::array<bool, 2>, 3> open{};
  std::array<double, 3> lo{}, hi{};
  bool has_open_face() const {
    for (const auto& axis : open)
      if (axis[0] || axis[1]) return true;
    return false;
  }
  /// Whether a point (x, y, w) lies beyond an open face: G2P's flag and the outflow removal.
  bool beyond_open_face(const double point[3]) const {
    for (int d = 0; d < 3; ++d)
      if ((open[d][0] && point[d] < lo[d]) || (open[d][1] && point[d] > hi[d])) return true;
    return false;
  }
};

/// Updates v_p and writes the step's displacement dt sum N_i v_i^L into `displacement`; positions
/// are moved only after the strain pass, so every transfer of a step uses the weights at x_p^k.
template <class Shape, class Terrain>
GatherResult gather_from_grid(ParticleStore& particles, const CellSort& sort, Grid& grid,
                              const std::array<std::span<double>, 3>& displacement, std::vector<double>& block_damping,
                              const GatherOptions& options, ColourPassTiming* timing = nullptr,
                              BlockBuffers* buffers = nullptr);  // the remap into the blocks' boxes (as scatter_to_grid)

/// Per-particle strain and spin increments of a range, structure of arrays.
struct StrainIncrements {
  static constexpr std::size_t kCapacity = 256;
  std::array<std::array<double, kCapacity>, 6> strain;  // Voigt, tensor components
  std::array<std::array<double, kCapacity>, 3> spin;    // w_yz, w_xz, w_xy
};

/// Strain increments of particles [begin, end) (end - begin <= kCapacity) from the node velocities
/// `node_velocity` (v^{k+1} after the MUSL remap, v^L for USL).
template <class Shape, class Terrain>
void strain_increments(const ParticleStore& particles, const Grid& grid,
                       const NodeVectors& node_velocity, double dt, std::size_t begin,
                       std::size_t end, StrainIncrements& out);

}  // namespace talus
