#pragma once
// The MLS smoother's internals that its two fits share (smoothing/mls_strain_smoother.cpp: one fit per
// particle; smoothing/mls_cell_fit.cpp: one fit per cell): the arguments of a pass, the work units
// the threads take, and the fit's solve with its guard. Compiled once, not per instruction set, so
// that every path decides the guard with the same code.
#include "talus/grid/grid.hpp"
#include "talus/particles/cell_sort.hpp"
#include "talus/particles/particle_store.hpp"
#include "talus/smoothing/mls_stored_weights.hpp"
#include "talus/smoothing/mls_strain_smoother.hpp"

#include <Eigen/Cholesky>
#include <Eigen/Core>

#include <array>
#include <cmath>
#include <cstdint>
#include <vector>

namespace talus {
namespace mls_detail {


/// The smoother's work units: the (i, j) columns of cells along k of every block (a group of
/// particles never spans two), the blocks heaviest first (CellSort::blocks_in_work_order). A unit
/// of bc cells balances the threads where whole blocks of bc^3 cells would not: a 200 000-particle
/// column has 54 blocks.
struct WorkUnits {
  explicit WorkUnits(const CellSort& sort)
      : order(sort.blocks_in_work_order()), bc(static_cast<std::size_t>(sort.block_cells())), columns(bc * bc) {}
  std::size_t count() const { return order.size() * columns; }
  std::size_t block(std::int64_t u) const { return order[static_cast<std::size_t>(u) / columns]; }
  std::size_t first_cell(std::int64_t u) const { return (static_cast<std::size_t>(u) % columns) * bc; }  // in the block
  const std::vector<std::uint32_t>& order;
  std::size_t bc, columns;
};

/// The arguments of one smoothing pass, for the per-target entry point.
struct MlsPass {
  const ParticleStore* particles;
  const CellSort* sort;
  const GridGeometry* grid;
  std::array<const double*, 6> in;
  std::array<double*, 6> out;
  const std::vector<std::uint8_t>* smooth_body;
  int degree, axis_count;
  std::array<int, 3> axes;
  double radius, min_rcond;
  bool cell_fit;         // MlsVariant::Cell: one fit per cell
  double search_radius;  // the cells walked: radius, plus the drift since the sort
  double* unit_seconds;  // null, or per work unit (WorkUnits order): its seconds
  MlsStoredWeights* record = nullptr;  // the particle fit's weights, kept (the `reused` variant)
};

/// What both fits read of a pass as they walk its blocks' cells: `const PassCells cells(pass);`
/// (not a structured binding: clang before 16 cannot capture one in the fits' lambdas).
struct PassCells {
  const ParticleStore& P;
  const CellSort& sort;
  const GridGeometry& grid;
  int bc;                                      // block edge in cells
  std::size_t cells_per_block;                 // bc^3
  const std::vector<std::uint32_t>& cell_start;  // the sorted store's range of each cell
  double rg;                                   // the search radius in cells
  explicit PassCells(const MlsPass& pass)
      : P(*pass.particles),
        sort(*pass.sort),
        grid(*pass.grid),
        bc(sort.block_cells()),
        cells_per_block(static_cast<std::size_t>(bc) * bc * bc),
        cell_start(sort.cell_start()),
        rg(pass.search_radius / grid.h) {}
};

/// The fit's solve for a well-conditioned A (the common case), in plain fixed-size loops that the
/// compiler unrolls: Cholesky A = L L^T, then A^-1 = L^-T L^-1 explicitly, a = A^-1 e_0 its first
/// column, and the exact reciprocal condition number 1 / (|A|_1 |A^-1|_1). Eigen's rcond() is an
/// estimate of the same quantity from below for |A^-1|_1, so it is never smaller than the exact
/// value: when the exact one clears 2 * min_rcond (the factor 2 absorbs round-off in A^-1), the
/// guard passes for certain. Returns false otherwise (not positive definite, or ill-conditioned,
/// or not finite): the caller then decides with Eigen's LLT and rcond() as before.
template <int T>
bool solve_well_conditioned(const double (&A)[T][T], double min_rcond, double (&a)[T], double (*inverse)[T] = nullptr) {
  double L[T][T] = {}, Li[T][T] = {};
  for (int j = 0; j < T; ++j) {
    double d = A[j][j];
    for (int k = 0; k < j; ++k) d -= L[j][k] * L[j][k];
    if (!(d > 0.0)) return false;
    L[j][j] = std::sqrt(d);
    const double inv = 1.0 / L[j][j];
    for (int i = j + 1; i < T; ++i) {
      double v = A[i][j];
      for (int k = 0; k < j; ++k) v -= L[i][k] * L[j][k];
      L[i][j] = v * inv;
    }
    Li[j][j] = inv;
  }
  for (int j = 0; j < T; ++j)  // L^-1, lower triangular, column by column
    for (int i = j + 1; i < T; ++i) {
      double v = 0.0;
      for (int k = j; k < i; ++k) v += L[i][k] * Li[k][j];
      Li[i][j] = -v * Li[i][i];
    }
  double a_norm = 0.0, ainv_norm = 0.0;  // 1-norms: largest column sum of magnitudes
  for (int c = 0; c < T; ++c) {
    double sa = 0.0, si = 0.0;
    for (int r = 0; r < T; ++r) {
      double v = 0.0;  // (A^-1)_rc = sum_k (L^-1)_kr (L^-1)_kc, k >= max(r, c)
      for (int k = r > c ? r : c; k < T; ++k) v += Li[k][r] * Li[k][c];
      if (c == 0) a[r] = v;
      if (inverse) inverse[r][c] = v;
      sa += std::abs(A[r][c]);
      si += std::abs(v);
    }
    a_norm = sa > a_norm ? sa : a_norm;
    ainv_norm = si > ainv_norm ? si : ainv_norm;
  }
  return a_norm * ainv_norm * (2.0 * min_rcond) <= 1.0;  // false for NaN or inf
}

/// The fit's coefficients a = A^-1 F(0), F(0) = e_0 (Edo & Matsubara 2015, eq. 42, 46), with the
/// guard: false for a (nearly) singular A. Compiled once (not per target), so every path decides
/// the guard with the same code.
template <int T>
[[gnu::noinline]] bool solve_fit(const double (&A)[T][T], double min_rcond, double (&a)[T]) {
  using MatT = Eigen::Matrix<double, T, T>;
  using VecT = Eigen::Matrix<double, T, 1>;
  if (solve_well_conditioned<T>(A, min_rcond, a)) return true;
  const MatT Am = Eigen::Map<const Eigen::Matrix<double, T, T, Eigen::RowMajor>>(&A[0][0]);
  const Eigen::LLT<MatT> llt(Am);
  bool ok = llt.info() == Eigen::Success && llt.rcond() >= min_rcond;
  VecT av;
  if (ok) av = llt.solve(VecT::Unit(0));
  ok = ok && av.allFinite();
  for (int r = 0; r < T; ++r) a[r] = ok ? av[r] : 0.0;
  return ok;
}

/// A^-1 for the one-fit-per-cell variant, with solve_fit's guard: the well-conditioned case in
/// the plain loops, the others decided by Eigen's LLT and rcond(). False for a (nearly) singular A.
template <int T>
[[gnu::noinline]] bool invert_fit(const double (&A)[T][T], double min_rcond, double (&inverse)[T][T]) {
  using MatT = Eigen::Matrix<double, T, T>;
  double a[T];
  if (solve_well_conditioned<T>(A, min_rcond, a, inverse)) return true;
  const MatT Am = Eigen::Map<const Eigen::Matrix<double, T, T, Eigen::RowMajor>>(&A[0][0]);
  const Eigen::LLT<MatT> llt(Am);
  bool ok = llt.info() == Eigen::Success && llt.rcond() >= min_rcond;
  MatT inv = MatT::Zero();
  if (ok) inv = llt.solve(MatT::Identity());
  ok = ok && inv.allFinite();
  for (int r = 0; r < T; ++r)
    for (int c = 0; c < T; ++c) inverse[r][c] = ok ? inv(r, c) : 0.0;
  return ok;
}

/// The one-fit-per-cell variant (MlsVariant::Cell) of a pass, on the path core/simd_dispatch.hpp
/// selects (smoothing/mls_cell_fit.cpp).
MlsCounts smooth_cell_fits(const MlsPass& pass);

}  // namespace mls_detail
}  // namespace talus
