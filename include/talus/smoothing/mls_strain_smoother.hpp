#pragma once
// MlsStrainSmoother: replaces each particle's strain increment by a moving-least-squares fit of
// its neighbours' increments (Edo & Matsubara 2015, eq. 38-46), between the strain pass and the material update
// (Edo & Matsubara 2015, eq. 54). For particle p with the n neighbours I of its body within the radius h:
//   A   = sum_I W(r_I, h) F(u_I) F(u_I)^T                         (eq. 42)
//   B   = [W_1 F(u_1), ..., W_n F(u_n)]                           (eq. 43)
//   Phi_I = F(u_p)^T (A^-1 B)_{:,I}                               (eq. 46)
//   d_eps_p <- sum_I Phi_I d_eps_I                                (eq. 45, each of the 6 components)
// with u_I = (x_I - x_p) / h: positions relative to the particle, scaled by the radius, so A is
// well scaled and F(u_p) = F(0) = e_0. Then d_eps_p = a^T sum_I W_I F(u_I) d_eps_I with a = A^-1 e_0:
// one factorisation of A per particle serves all six components.
//
// Guard: a particle with fewer neighbours than basis terms, or whose A is not positive definite or
// has a reciprocal condition number below `min_rcond`, keeps its own increment and is counted.
//
// Neighbours are found through the cell sort: the cells within the radius, their particle ranges
// from CellSort::cell_start(). The sort may be older than the positions: when no particle has moved
// more than `drift` since it, the cells within radius + drift hold every neighbour (the solver
// re-sorts once the drift passes a quarter of a cell). Particles are fitted a register's worth at a time, one
// per vector lane, over the candidates near their group (weight 0 outside a particle's ball); each
// particle's sums run over its neighbours in a fixed order (cells in (i, j, k) order, then store
// order), so the output is bit-identical for any thread count and on every instruction-set path
// (core/simd_dispatch.hpp).
#include "talus/grid/grid.hpp"
#include "talus/particles/cell_sort.hpp"
#include "talus/particles/particle_store.hpp"
#include "talus/smoothing/mls_basis.hpp"
#include "talus/smoothing/mls_settings.hpp"

#include <array>
#include <cstddef>
#include <cstdint>
#include <vector>

namespace talus {

class MlsStoredWeights;

struct MlsCounts {
  std::size_t smoothed = 0;    // particles whose increment was replaced by the fit
  std::size_t unsmoothed = 0;  // particles of smoothed bodies left as they were by the guard
};

class MlsStrainSmoother {
 public:
  MlsStrainSmoother(const MlsSettings& settings, double cell_size);

  const MlsSettings& settings() const { return settings_; }
  double radius() const { return radius_; }
  int term_count() const;

  /// Smooth the six strain-increment arrays `in` (indexed like the store) into `out` (no
  /// aliasing). Particles of a body b with smooth_body[b] == 0 are copied unchanged and are nobody's
  /// neighbours outside their own body. `sort` is the sort of positions at most `drift` metres
  /// from the current ones (0: of the current positions). The drift widens the search, not the
  /// fit: a particle's result depends on the candidates' order, which is the sort's, not on the
  /// drift. The one-fit-per-cell variant fits the particles of a sorted cell about its centre, so
  /// it wants the sort of the current positions (the solver sorts every step for it). The threads take work units in turn: the (i, j) columns of cells along k of
  /// every block, the blocks heaviest first (CellSort::blocks_in_work_order()). With `unit_seconds`
  /// (the work recorder) the seconds each unit took, in that order. With `keep` (the particle fit
  /// only) the fits' weights are stored there, for MlsStoredWeights::apply in later steps.
  MlsCounts smooth(const ParticleStore& particles, const CellSort& sort, const GridGeometry& grid,
                   const std::array<const double*, 6>& in, const std::array<double*, 6>& out,
                   const std::vector<std::uint8_t>& smooth_body, double drift = 0.0,
                   std::vector<double>* unit_seconds = nullptr, MlsStoredWeights* keep = nullptr) const;
  /// The particles of each work unit of smooth(), in its order.
  static std::vector<std::uint32_t> work_unit_particles(const CellSort& sort);

 private:
  MlsSettings settings_;
  double radius_ = 0.0;
  std::array<int, 3> axis_list_{0, 1, 2};  // the active axes, in order
  int axis_count_ = 3;
};

}  // namespace talus
