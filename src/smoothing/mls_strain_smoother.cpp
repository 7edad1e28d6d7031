// The MLS strain smoother (Edo & Matsubara 2015, eq. 38-46), compiled once per instruction set by
// Highway's foreach_target and dispatched at run time (core/simd_dispatch.hpp).
//
// Particles are fitted in groups of kGroup, one particle per lane: a group's candidates (the
// particles near the group's box) are gathered once, and every candidate is evaluated for all the
// lanes at once, with weight exactly zero outside a particle's ball or body. No lane ever reads
// another, and each lane's sums run over the candidates in the same fixed order (cells in (i, j, k)
// order, then store order), so a particle's result does not depend on the lane width, on the group
// it falls in, or on the thread count. The lanes are GCC vector extensions of one register's
// width, with the same operations in the same order on every path (no fused multiply-add: the
// build sets -ffp-contract=off).
#undef HWY_TARGET_INCLUDE
#define HWY_TARGET_INCLUDE "smoothing/mls_strain_smoother.cpp"
#include <hwy/foreach_target.h>  // IWYU pragma: keep

#include <hwy/aligned_allocator.h>
#include <hwy/highway.h>
#include <omp.h>

#include "talus/core/error.hpp"
#include "talus/core/simd_dispatch.hpp"
#include "talus/smoothing/mls_strain_smoother.hpp"

#include <Eigen/Cholesky>
#include <Eigen/Core>
#include <fmt/core.h>

#include <algorithm>
#include <cmath>
#include <cstring>
#include <stdexcept>
#include <vector>

#ifndef TALUS_MLS_SOLVE_DEFINED  // once, not per target
#define TALUS_MLS_SOLVE_DEFINED
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

/// The fit's coefficients a = A^-1 F(0), F(0) = e_0 (Edo & Matsubara 2015, eq. 42, 45), with the
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

}  // namespace mls_detail
}  // namespace talus
#endif

// Lane vectors live only inside this file's inlined functions: no call passes one by value.
#pragma GCC diagnostic ignored "-Wpsabi"

HWY_BEFORE_NAMESPACE();
namespace talus {
namespace HWY_NAMESPACE {
namespace {

using mls_detail::MlsPass;

// Particles fitted together, one per lane: one vector register of doubles (8 with AVX-512, 4
// with AVX2, 2 on the baseline), so that A's sums stay in registers. A particle's result does not
// depend on its group, so the paths agree although their groups differ.
constexpr int kGroup = HWY_LANES(double) > 2 ? HWY_LANES(double) : 2;
typedef double Lanes __attribute__((vector_size(kGroup * sizeof(double)), may_alias));

/// Distance (in cells) from the grid-coordinate interval [lo, hi] to the cell [i, i + 1). With
/// lo = hi = x this is the distance from the point x; it only shrinks as [lo, hi] grows.
inline double gap_to_cell(int i, double lo, double hi) {
  const double a = i - hi, b = lo - (i + 1);
  const double g = a > b ? a : b;
  return g > 0.0 ? g : 0.0;
}

/// Cubic spline of Edo & Matsubara 2015, eq. 39 for 0 <= s < 1, the same arithmetic as mls_weight
/// but as one select, for a lane vector.
template <class V>
[[gnu::always_inline]] inline V weight_inside(V s) {
  const V inner = 2.0 / 3.0 - 4.0 * s * s + 4.0 * s * s * s;
  const V outer = 4.0 / 3.0 - 4.0 * s + 4.0 * s * s - 4.0 / 3.0 * s * s * s;
  return s < 0.5 ? inner : outer;
}

/// The square root of every lane (correctly rounded on every target).
template <class V>
[[gnu::always_inline]] inline V sqrt_lanes(V x) {
  V r;
  for (int v = 0; v < static_cast<int>(sizeof(V) / sizeof(double)); ++v) r[v] = __builtin_sqrt(x[v]);
  return r;
}

/// Thread-local scratch of one group. Buffers only grow, so after the first groups a thread
/// allocates nothing.
struct GroupScratch {
  // Candidates: the store indices of the particles within the radius of the box of the group's
  // cells (idx), and of those the ones within the radius of the group's own box (group_idx).
  std::vector<std::int64_t> idx, group_idx;
  // The gathered candidates' positions as columns, padded with +inf to whole vectors, for the
  // groups' own filters (built once per gathered list, when a group is smaller than its cells).
  std::array<std::vector<double>, 3> idx_x;
  bool idx_x_current = false;
  // Per candidate, the lanes' scaled offsets along the basis axes and eq. 39 weights (pass 1 ->
  // pass 2): 4 x kGroup doubles, aligned for whole-vector loads.
  hwy::AlignedFreeUniquePtr<double[]> lanes;
  std::size_t lanes_capacity = 0;  // candidates
  Lanes* lane_array(int k) { return reinterpret_cast<Lanes*>(lanes.get()) + k * lanes_capacity; }
  // The one-fit-per-cell variant: the candidates' x, y, z, six increments and body flag as columns.
  std::array<std::vector<double>, 10> cand;
};

/// The box of the group's particles, in grid coordinates (the search) and in metres (the
/// candidate filter). The box, not the cell, bounds the search, so a particle off its sorted cell
/// still finds all its neighbours.
struct ParticleBox {
  double lo[3] = {HUGE_VAL, HUGE_VAL, HUGE_VAL}, hi[3] = {-HUGE_VAL, -HUGE_VAL, -HUGE_VAL};
  double xlo[3] = {HUGE_VAL, HUGE_VAL, HUGE_VAL}, xhi[3] = {-HUGE_VAL, -HUGE_VAL, -HUGE_VAL};
};

/// Squared distance from x to the box [xlo, xhi], NaN for a position that is not finite (the
/// `0 * sum` term: zero for finite coordinates, so it never changes a finite distance).
template <class V>
[[gnu::always_inline]] inline V gap2_to_box(const V (&x)[3], const V (&xlo)[3], const V (&xhi)[3], V zero) {
  V g2 = zero;
  for (int d = 0; d < 3; ++d) {
    const V below = xlo[d] - x[d], above = x[d] - xhi[d];
    const V gap = below > above ? below : above;
    g2 += gap > zero ? gap * gap : zero;
  }
  return g2 + zero * (x[0] + x[1] + x[2]);
}

/// Store, at out, value(lane) for the lanes set in m, in lane order, and return how many (out
/// needs room for a whole vector). One unconditional store per lane, advanced by the lane's
/// bit: Highway 1.0.3's CompressStore of 64-bit lanes on AVX-512 is the compressing store to memory,
/// which AMD's Zen 4 runs as microcode, and its Compress copies a 2 KiB table onto the stack at
/// every call (GCC 12); either took about 40% of the candidate search.
template <class DI, class M, class Value>
[[gnu::always_inline]] inline std::size_t store_kept(DI di, M m, Value value, std::int64_t* out) {
  namespace hn = hwy::HWY_NAMESPACE;
  constexpr std::size_t kMaxLanes = HWY_MAX_BYTES / sizeof(std::int64_t);
  std::uint8_t bits[(kMaxLanes + 7) / 8] = {};
  hn::StoreMaskBits(di, m, bits);
  std::size_t n = 0;
  for (std::size_t v = 0; v < hn::Lanes(di); ++v) {
    out[n] = value(v);
    n += (bits[v / 8] >> (v % 8)) & 1u;
  }
  return n;
}
/// The indices q + lane of the lanes set in m.
template <class DI, class M>
[[gnu::always_inline]] inline std::size_t store_kept_indices(DI di, M m, std::int64_t q, std::int64_t* out) {
  return store_kept(di, m, [q](std::size_t v) { return q + static_cast<std::int64_t>(v); }, out);
}

/// gap2_to_box for a vector of positions, operation for operation (the same bits per lane).
template <class D, class V>
[[gnu::always_inline]] inline V gap2_to_box_lanes(D, const V (&x)[3], const V (&xlo)[3], const V (&xhi)[3], V zero) {
  namespace hn = hwy::HWY_NAMESPACE;
  V g2 = zero;
  for (int k = 0; k < 3; ++k) {
    const V below = hn::Sub(xlo[k], x[k]), above = hn::Sub(x[k], xhi[k]);
    const V gap = hn::IfThenElse(hn::Gt(below, above), below, above);
    g2 = hn::Add(g2, hn::IfThenElseZero(hn::Gt(gap, zero), hn::Mul(gap, gap)));
  }
  return hn::Add(g2, hn::Mul(zero, hn::Add(hn::Add(x[0], x[1]), x[2])));
}

/// Append, to the candidates, the indices of the particles [q0, q1) that lie within the radius of
/// the box: the others are nobody's neighbour in the group (the cells gathered hold about twice as
/// many as the ball around the box, at a radius of 1 cell). keep2 has a margin, so a candidate at
/// the radius stays within round-off; the exact test per lane decides. A particle at a non-finite
/// position is never kept.
[[gnu::always_inline]] inline void append_candidates(GroupScratch& S, std::size_t& nc, const ParticleStore& P,
                                                     const ParticleBox& box, double keep2, std::uint32_t q0,
                                                     std::uint32_t q1) {
  namespace hn = hwy::HWY_NAMESPACE;
  const hn::ScalableTag<double> d;
  const hn::RebindToSigned<decltype(d)> di;
  const std::size_t N = hn::Lanes(d);
  if (S.idx.size() < nc + (q1 - q0) + N) S.idx.resize(std::max<std::size_t>(nc + (q1 - q0) + N, 2 * S.idx.size()));
  using V = hn::Vec<decltype(d)>;
  const V zero = hn::Zero(d);
  const V xlo[3] = {hn::Set(d, box.xlo[0]), hn::Set(d, box.xlo[1]), hn::Set(d, box.xlo[2])};
  const V xhi[3] = {hn::Set(d, box.xhi[0]), hn::Set(d, box.xhi[1]), hn::Set(d, box.xhi[2])};
  const V keep = hn::Set(d, keep2);
  std::uint32_t q = q0;
  for (; q + N <= q1; q += N) {
    const V x[3] = {hn::LoadU(d, P.x[0].data() + q), hn::LoadU(d, P.x[1].data() + q), hn::LoadU(d, P.x[2].data() + q)};
    const auto m = hn::RebindMask(di, hn::Lt(gap2_to_box_lanes(d, x, xlo, xhi, zero), keep));
    nc += store_kept_indices(di, m, static_cast<std::int64_t>(q), S.idx.data() + nc);
  }
  for (; q < q1; ++q) {
    const double x[3] = {P.x[0][q], P.x[1][q], P.x[2][q]};
    const double g2 = gap2_to_box<double>(x, box.xlo, box.xhi, 0.0);
    S.idx[nc] = q;
    nc += g2 < keep2 ? 1 : 0;
  }
}

/// Of the nc gathered candidates, those within the radius (keep2) of the group's box [xlo, xhi],
/// in their order, into S.group_idx; returns how many. The same test as append_candidates on whole
/// vectors of the candidates' positions, which are copied into columns once per gathered list
/// (the 2 groups of a cell on AVX2, 4 on the baseline, share it).
inline std::size_t filter_for_group(GroupScratch& S, const ParticleStore& P, std::size_t nc, const double (&box_lo)[3],
                                    const double (&box_hi)[3], double keep2) {
  namespace hn = hwy::HWY_NAMESPACE;
  const hn::ScalableTag<double> d;
  const hn::RebindToSigned<decltype(d)> di;
  const std::size_t N = hn::Lanes(d);
  const std::size_t padded = (nc + N - 1) / N * N;
  if (!S.idx_x_current) {
    for (int k = 0; k < 3; ++k) {
      std::vector<double>& column = S.idx_x[k];
      if (column.size() < padded) column.resize(std::max(padded, 2 * column.size()));
      for (std::size_t I = 0; I < nc; ++I) column[I] = P.x[k][S.idx[I]];
      for (std::size_t I = nc; I < padded; ++I) column[I] = HUGE_VAL;  // never kept (g2 is NaN)
    }
    S.idx_x_current = true;
  }
  if (S.group_idx.size() < padded) S.group_idx.resize(std::max(padded, S.idx.size()));
  using V = hn::Vec<decltype(d)>;
  const V zero = hn::Zero(d), keep = hn::Set(d, keep2);
  const V xlo[3] = {hn::Set(d, box_lo[0]), hn::Set(d, box_lo[1]), hn::Set(d, box_lo[2])};
  const V xhi[3] = {hn::Set(d, box_hi[0]), hn::Set(d, box_hi[1]), hn::Set(d, box_hi[2])};
  const std::int64_t* idx = S.idx.data();
  std::size_t ng = 0;
  for (std::size_t I = 0; I < padded; I += N) {
    const V x[3] = {hn::LoadU(d, S.idx_x[0].data() + I), hn::LoadU(d, S.idx_x[1].data() + I),
                    hn::LoadU(d, S.idx_x[2].data() + I)};
    const auto m = hn::RebindMask(di, hn::Lt(gap2_to_box_lanes(d, x, xlo, xhi, zero), keep));
    ng += store_kept(di, m, [&](std::size_t v) { return idx[I + v]; }, S.group_idx.data() + ng);
  }
  return ng;
}

/// Block coordinate and cell within the block of padded cell c along one axis (blocks start at
/// `shift`); a cell before the first block gets a negative block, which no block has.
struct BlockCell {
  int block, local;
};
inline BlockCell block_cell(int c, int shift, int bc) {
  const int from_first = c - shift;
  if (from_first < 0) return {-1, 0};
  const int block = from_first / bc;
  return {block, from_first - block * bc};
}

/// Visit the particle ranges [q0, q1) of the cells that meet the ball of radius rg (cells) around
/// any point of the box, in a fixed order: columns in (i, j) order, along k in store order. Along
/// k the cells of one block are contiguous in the store: one range per block. The block and local
/// cell of each i and j are found once (a group walks about 9 columns of 3 cells each).
template <class Visit>
[[gnu::always_inline]] inline void for_each_candidate_range(const MlsPass& pass, const ParticleBox& box, double rg,
                                                            Visit&& visit) {
  const CellSort& sort = *pass.sort;
  const int bc = sort.block_cells();
  const std::array<int, 3>& shift = sort.block_shift();
  const std::size_t cells_per_block = static_cast<std::size_t>(bc) * bc * bc;
  const std::vector<std::uint32_t>& cell_start = sort.cell_start();
  const double rg2 = rg * rg;
  const int reach = static_cast<int>(std::ceil(rg));
  const int i0 = static_cast<int>(std::floor(box.lo[0])), i1 = static_cast<int>(std::floor(box.hi[0]));
  const int j0 = static_cast<int>(std::floor(box.lo[1])), j1 = static_cast<int>(std::floor(box.hi[1]));
  const int j_first = std::max(0, j0 - reach), j_stop = j1 + reach + 1;
  // The j columns' blocks, once for all i (a box is a cell or two wide, so a few entries).
  constexpr int kColumns = 16;
  BlockCell j_cells[kColumns];
  const bool j_listed = j_stop - j_first <= kColumns;
  if (j_listed)
    for (int j = j_first; j < j_stop; ++j) j_cells[j - j_first] = block_cell(j, shift[1], bc);
  for (int i = std::max(0, i0 - reach); i <= i1 + reach; ++i) {
    const double gi = gap_to_cell(i, box.lo[0], box.hi[0]);
    if (gi * gi >= rg2) continue;
    const BlockCell ci = block_cell(i, shift[0], bc);
    for (int j = j_first; j < j_stop; ++j) {
      const double gj = gap_to_cell(j, box.lo[1], box.hi[1]);
      const double rem = rg2 - gi * gi - gj * gj;
      if (rem <= 0.0) continue;
      const double half = std::sqrt(rem);
      const BlockCell cj = j_listed ? j_cells[j - j_first] : block_cell(j, shift[1], bc);
      int k = std::max(0, static_cast<int>(std::floor(box.lo[2] - half)));
      const int k_last = static_cast<int>(std::floor(box.hi[2] + half));
      BlockCell ck = block_cell(k, shift[2], bc);
      if (ck.block < 0) {  // cells before the first block hold no particles
        k = shift[2];
        ck = {0, 0};
      }
      while (k <= k_last) {
        const int k_end = std::min(k_last, k + (bc - 1 - ck.local));  // last cell of this block along k
        const long long cb = sort.active_block(ci.block, cj.block, ck.block);
        if (cb >= 0) {
          const std::size_t cbase = static_cast<std::size_t>(cb) * cells_per_block;
          const std::size_t l0 = static_cast<std::size_t>((ci.local * bc + cj.local) * bc + ck.local);
          const std::size_t l1 = l0 + static_cast<std::size_t>(k_end - k);
          visit(cell_start[cbase + l0], cell_start[cbase + l1 + 1]);
        }
        k = k_end + 1;
        ck = {ck.block + 1, 0};
      }
    }
  }
}

/// Gather, into S, the particles near the box from the cells that meet the ball of radius rg
/// (cells) around any point of the box: the same walk as for a single particle (lo = hi), so each
/// particle's own search is a subset, in the same order. Returns the candidate count.
inline std::size_t gather_candidates(GroupScratch& S, const MlsPass& pass, const ParticleBox& box, double rg) {
  const double keep2 = pass.radius * pass.radius * (1.0 + 1e-9);
  std::size_t nc = 0;
  for_each_candidate_range(pass, box, rg, [&](std::uint32_t q0, std::uint32_t q1) {
    append_candidates(S, nc, *pass.particles, box, keep2, q0, q1);
  });
  return nc;
}

template <class V>
[[gnu::always_inline]] inline V abs_lanes(V x) {
  V r;
  for (int v = 0; v < kGroup; ++v) r[v] = __builtin_fabs(x[v]);
  return r;
}

/// mls_detail::solve_well_conditioned for every lane at once, operation for operation (so each
/// lane gets the scalar function's bits), from A's upper triangle acc. Returns, per lane, whether
/// the scalar function would have returned true; a lane's a is then its result.
template <int T>
[[gnu::always_inline]] inline auto solve_well_conditioned_lanes(const Lanes* acc, double min_rcond, Lanes (&a)[T]) {
  auto upper = [](int r, int c) { return r * T - r * (r - 1) / 2 + (c - r); };  // index of A[r][c], r <= c
  const Lanes zero = {};
  Lanes L[T][T] = {}, Li[T][T] = {};
  auto ok = zero == zero;
  for (int j = 0; j < T; ++j) {
    Lanes d = acc[upper(j, j)];
    for (int k = 0; k < j; ++k) d -= L[j][k] * L[j][k];
    ok &= d > zero;
    L[j][j] = sqrt_lanes(ok ? d : zero + 1.0);
    const Lanes inv = 1.0 / L[j][j];
    for (int i = j + 1; i < T; ++i) {
      Lanes v = acc[upper(j, i)];
      for (int k = 0; k < j; ++k) v -= L[i][k] * L[j][k];
      L[i][j] = v * inv;
    }
    Li[j][j] = inv;
  }
  for (int j = 0; j < T; ++j)
    for (int i = j + 1; i < T; ++i) {
      Lanes v = zero;
      for (int k = j; k < i; ++k) v += L[i][k] * Li[k][j];
      Li[i][j] = -v * Li[i][i];
    }
  Lanes a_norm = zero, ainv_norm = zero;
  for (int c = 0; c < T; ++c) {
    Lanes sa = zero, si = zero;
    for (int r = 0; r < T; ++r) {
      Lanes v = zero;
      for (int k = r > c ? r : c; k < T; ++k) v += Li[k][r] * Li[k][c];
      if (c == 0) a[r] = v;
      sa += abs_lanes(acc[r <= c ? upper(r, c) : upper(c, r)]);
      si += abs_lanes(v);
    }
    a_norm = sa > a_norm ? sa : a_norm;
    ainv_norm = si > ainv_norm ? si : ainv_norm;
  }
  return ok & (a_norm * ainv_norm * (2.0 * min_rcond) <= 1.0);
}

/// Smooth the n <= kGroup particles p[] (of smoothed bodies) together (Edo & Matsubara 2015,
/// eq. 42-46). Pass 1 sums, per lane, A = sum_I W_I F(u_I) F(u_I)^T (eq. 42) over every candidate
/// I, W_I = 0 outside the lane's ball or body; each lane then solves a = A^-1 e_0 (eq. 45, the
/// guard); pass 2 sums d_eps_p = sum_I W_I (a^T F(u_I)) d_eps_I (eq. 46, a^T B d_eps per candidate).
/// Outside a lane's ball W_I = 0 and F(u_I) is finite, so the term is a zero that leaves the sum
/// unchanged. In pass 2 that holds while the candidates' inputs are finite; a non-finite input
/// makes every lane's sum non-finite, and pass 2 is then redone with the terms outside the ball
/// selected away (a NaN input stays inside its own ball, as with a neighbour list).
template <int Degree, int Axes>
void smooth_group(GroupScratch& S, const std::int64_t* idx, std::size_t nc, const MlsPass& pass, const std::uint32_t* p,
                  int n, std::size_t& smoothed, std::size_t& unsmoothed) {
  constexpr int T = mls_term_count(Degree, Axes);
  constexpr int NA = T * (T + 1) / 2;  // upper triangle of A
  const ParticleStore& P = *pass.particles;
  const double inv_radius = 1.0 / pass.radius;
  Lanes xp[3], body;
  for (int v = 0; v < kGroup; ++v) {  // padding lanes repeat the first particle; their results are dropped
    const std::uint32_t q = p[v < n ? v : 0];
    for (int d = 0; d < 3; ++d) xp[d][v] = P.x[d][q];
    body[v] = P.body[q];
  }
  if (S.lanes_capacity < nc) {
    S.lanes_capacity = std::max(nc, S.idx.size());
    S.lanes = hwy::AllocateAligned<double>(4 * kGroup * S.lanes_capacity);
  }
  const double *x0 = P.x[0].data(), *x1 = P.x[1].data(), *x2 = P.x[2].data();
  const std::uint16_t* pbody = P.body.data();
  Lanes* uu[3] = {S.lane_array(0), S.lane_array(1), S.lane_array(2)};
  Lanes* ww = S.lane_array(3);
  const Lanes zero = {};
  // Pass 1: offsets, weights and the sums of A.
  Lanes acc[NA] = {}, count = {};
  for (std::size_t I = 0; I < nc; ++I) {
    const std::int64_t q = idx[I];
    const Lanes d0 = (x0[q] - xp[0]) * inv_radius, d1 = (x1[q] - xp[1]) * inv_radius, d2 = (x2[q] - xp[2]) * inv_radius;
    const Lanes r2 = d0 * d0 + d1 * d1 + d2 * d2;
    const auto in = (r2 < 1.0) & (static_cast<double>(pbody[q]) == body);
    const Lanes s = sqrt_lanes(in ? r2 : zero);
    const Lanes w = in ? weight_inside(s) : zero;  // Edo & Matsubara 2015, eq. 39
    Lanes u[Axes];  // finite: the lanes and the candidates have finite positions
    if constexpr (Axes == 3) {
      u[0] = d0, u[1] = d1, u[2] = d2;
    } else {
      const Lanes dd[3] = {d0, d1, d2};
      for (int ax = 0; ax < Axes; ++ax) u[ax] = dd[pass.axes[ax]];
    }
    count += in ? zero + 1.0 : zero;
    for (int ax = 0; ax < Axes; ++ax) uu[ax][I] = u[ax];
    ww[I] = w;
    Lanes F[T], WF[T];
    mls_basis<Degree, Axes>(u, F);
    for (int r = 0; r < T; ++r) WF[r] = w * F[r];
    int e = 0;
    for (int r = 0; r < T; ++r)
      for (int c = r; c < T; ++c, ++e) acc[e] += WF[r] * F[c];
  }
  // Each lane's solve (the guard: too few neighbours, or a (nearly) singular A): all lanes at once
  // where A is certainly well conditioned, Eigen's LLT and rcond() for the others.
  Lanes a[T];
  const auto fast = solve_well_conditioned_lanes<T>(acc, pass.min_rcond, a);
  bool ok[kGroup];
  for (int v = 0; v < kGroup; ++v) {
    ok[v] = v < n && count[v] >= T;
    if (ok[v] && !fast[v]) {
      double A[T][T], av[T];
      int e = 0;
      for (int r = 0; r < T; ++r)
        for (int c = r; c < T; ++c, ++e) A[r][c] = A[c][r] = acc[e][v];
      ok[v] = mls_detail::solve_fit<T>(A, pass.min_rcond, av);
      for (int r = 0; r < T; ++r) a[r][v] = av[r];
    }
    if (!ok[v])
      for (int r = 0; r < T; ++r) a[r][v] = 0.0;
  }
  // Pass 2: Phi_I = W_I a^T F(u_I) (eq. 45) times the candidates' increments (eq. 46).
  Lanes sum[6] = {};
  const double* in[6];
  for (int c = 0; c < 6; ++c) in[c] = pass.in[c];
  auto phi_of = [&](std::size_t I) {  // W_I a^T F(u_I)
    Lanes u[Axes], F[T];
    for (int ax = 0; ax < Axes; ++ax) u[ax] = uu[ax][I];
    mls_basis<Degree, Axes>(u, F);
    Lanes phi = a[0] * F[0];
    for (int r = 1; r < T; ++r) phi += a[r] * F[r];
    return phi * ww[I];
  };
  for (std::size_t I = 0; I < nc; ++I) {
    const Lanes phi = phi_of(I);
    for (int c = 0; c < 6; ++c) sum[c] += phi * in[c][idx[I]];
  }
  Lanes check = zero;
  for (int c = 0; c < 6; ++c) check += zero * sum[c];
  bool finite = true;
  for (int v = 0; v < kGroup; ++v) finite = finite && check[v] == 0.0;
  if (!finite) {
    for (int c = 0; c < 6; ++c) sum[c] = zero;
    for (std::size_t I = 0; I < nc; ++I) {
      const std::int64_t q = idx[I];
      const Lanes d0 = (x0[q] - xp[0]) * inv_radius, d1 = (x1[q] - xp[1]) * inv_radius,
                  d2 = (x2[q] - xp[2]) * inv_radius;
      const Lanes r2 = d0 * d0 + d1 * d1 + d2 * d2;
      const auto inside = (r2 < 1.0) & (static_cast<double>(pbody[q]) == body);
      const Lanes phi = phi_of(I);
      for (int c = 0; c < 6; ++c) sum[c] += inside ? phi * in[c][q] : zero;
    }
  }
  for (int v = 0; v < n; ++v) {
    const std::uint32_t q = p[v];
    for (int c = 0; c < 6; ++c) pass.out[c][q] = ok[v] ? sum[c][v] : pass.in[c][q];  // the guard: unsmoothed
    smoothed += ok[v] ? 1 : 0;
    unsmoothed += ok[v] ? 0 : 1;
  }
}

template <int Degree, int Axes>
MlsCounts smooth_impl(const MlsPass& pass) {
  const ParticleStore& P = *pass.particles;
  const CellSort& sort = *pass.sort;
  const GridGeometry& grid = *pass.grid;
  const std::vector<std::uint8_t>& smooth_body = *pass.smooth_body;
  const int bc = sort.block_cells();
  const std::size_t cells_per_block = static_cast<std::size_t>(bc) * bc * bc;
  const std::vector<std::uint32_t>& cell_start = sort.cell_start();
  const mls_detail::WorkUnits work(sort);
  const std::int64_t units = static_cast<std::int64_t>(work.count());
  const double rg = pass.search_radius / grid.h;  // radius in cells
  std::size_t smoothed = 0, unsmoothed = 0;
#pragma omp parallel reduction(+ : smoothed, unsmoothed)
  {
    GroupScratch S;
    std::uint32_t group[kGroup];
    int n = 0;
    // The group's cells as a store range [range_begin, range_end). The candidates are gathered for
    // the box of every particle in those cells that can be fitted, and kept for the next group
    // while its cells are the same: a cell of more particles than lanes (8 per cell on AVX2's 4
    // lanes) is then searched once, not once per group. A superset of a lane's neighbours changes
    // none of its bits (zero weights; see smooth_group), as between the paths' group sizes.
    std::uint32_t range_begin = 0, range_end = 0, gathered_begin = 0, gathered_end = 0;
    std::size_t nc = 0, fittable_in_range = 0;
    const double keep2 = pass.radius * pass.radius * (1.0 + 1e-9);  // as gather_candidates
    auto fittable = [&](std::uint32_t q) {
      return smooth_body[P.body[q]] && std::isfinite(P.x[0][q]) && std::isfinite(P.x[1][q]) && std::isfinite(P.x[2][q]);
    };
    auto flush = [&] {
      if (n == 0) return;
      if (range_begin != gathered_begin || range_end != gathered_end) {
        ParticleBox box;
        fittable_in_range = 0;
        for (std::uint32_t q = range_begin; q < range_end; ++q) {
          if (!fittable(q)) continue;
          ++fittable_in_range;
          for (int d = 0; d < 3; ++d) {
            const double x = P.x[d][q], xg = grid.to_grid(d, x);
            box.lo[d] = xg < box.lo[d] ? xg : box.lo[d];
            box.hi[d] = xg > box.hi[d] ? xg : box.hi[d];
            box.xlo[d] = x < box.xlo[d] ? x : box.xlo[d];
            box.xhi[d] = x > box.xhi[d] ? x : box.xhi[d];
          }
        }
        nc = gather_candidates(S, pass, box, rg);
        S.idx_x_current = false;
        gathered_begin = range_begin;
        gathered_end = range_end;
      }
      // A group of every fittable particle of its cells (one group per cell on AVX-512) has the
      // gathered box as its own: the gathered list is its list.
      if (static_cast<std::size_t>(n) == fittable_in_range) {
        smooth_group<Degree, Axes>(S, S.idx.data(), nc, pass, group, n, smoothed, unsmoothed);
        n = 0;
        return;
      }
      // The group's own box keeps its list short: the candidates within the radius of it, in the
      // cells' order, are those a search from the group's box alone would find, in its order.
      double xlo[3] = {HUGE_VAL, HUGE_VAL, HUGE_VAL}, xhi[3] = {-HUGE_VAL, -HUGE_VAL, -HUGE_VAL};
      for (int g = 0; g < n; ++g)
        for (int d = 0; d < 3; ++d) {
          const double x = P.x[d][group[g]];
          xlo[d] = x < xlo[d] ? x : xlo[d];
          xhi[d] = x > xhi[d] ? x : xhi[d];
        }
      const std::size_t ng = filter_for_group(S, P, nc, xlo, xhi, keep2);
      smooth_group<Degree, Axes>(S, S.group_idx.data(), ng, pass, group, n, smoothed, unsmoothed);
      n = 0;
    };
#pragma omp for schedule(dynamic, 1)
    for (std::int64_t u = 0; u < units; ++u) {
      const double unit_start = pass.unit_seconds ? omp_get_wtime() : 0.0;
      // Groups: up to kGroup particles from consecutive cells of one column along k (their box
      // stays about one cell wide); a cell joins the open group only if all of it fits. A group
      // never spans two columns (it is flushed at the end of each).
      const std::size_t base = work.block(u) * cells_per_block + work.first_cell(u);
      for (std::size_t l = 0; l < static_cast<std::size_t>(bc); ++l) {
        const std::uint32_t p_begin = cell_start[base + l], p_end = cell_start[base + l + 1];
        if (p_begin == p_end) continue;
        if (n > 0 && (static_cast<std::uint32_t>(n) + (p_end - p_begin) > kGroup || l == 0 ||
                      cell_start[base + l - 1] == cell_start[base + l]))
          flush();
        for (std::uint32_t q = p_begin; q < p_end; ++q) {
          if (!smooth_body[P.body[q]]) {  // not smoothed: copied, and nobody's neighbour
            for (int c = 0; c < 6; ++c) pass.out[c][q] = pass.in[c][q];
            continue;
          }
          if (!(std::isfinite(P.x[0][q]) && std::isfinite(P.x[1][q]) && std::isfinite(P.x[2][q]))) {
            for (int c = 0; c < 6; ++c) pass.out[c][q] = pass.in[c][q];  // no neighbours: the guard
            ++unsmoothed;
            continue;
          }
          if (n == kGroup) flush();
          if (n == 0) range_begin = p_begin;
          range_end = p_end;
          group[n++] = q;
        }
      }
      flush();
      if (pass.unit_seconds) pass.unit_seconds[u] = omp_get_wtime() - unit_start;
    }
  }
  return {smoothed, unsmoothed};
}

// ---- One fit per cell (MlsVariant::Cell) ---------------------------------------------------------
// One fit per cell and body, centred at the cell's centre x_c: A and the right-hand sides
// B_c = sum_I W_I F(u_I) d_eps_I,c (u_I = (x_I - x_c) / h, the weight centred at x_c), then the
// coefficients C = A^-1 B and, at each of the cell's particles, d_eps_p = F(u_p)^T C (Edo &
// Matsubara 2015, eq. 42-46 with x_c in place of x_p). Only the candidates within the radius of x_c
// are gathered (about 34 at a radius of 1 cell and 8 particles per cell, against the 216 of the
// 27 cells around it), and they run along the lanes: 8 at a time on every path (a vector of 8
// doubles: one AVX-512 register, two AVX2 or four SSE2 registers), each lane keeping its own
// partial sums, which are added in one fixed order at the end. So the sums, and the results, are
// bit-identical on every path and for any thread count.
constexpr int kCellLanes = 8;
typedef double CellLanes __attribute__((vector_size(kCellLanes * sizeof(double)), may_alias));

/// The lanes' partial sums added in a fixed order.
[[gnu::always_inline]] inline double lane_total(CellLanes v) {
  return ((v[0] + v[4]) + (v[2] + v[6])) + ((v[1] + v[5]) + (v[3] + v[7]));
}

/// Gather, into S.cand, the particles within the radius of the cell centre xc (with keep2's
/// margin: the kernel's exact test decides) from the store ranges of the cells that meet the ball:
/// x, y, z, the six increments, and 1 for a particle of `body` (0 otherwise), in walk order,
/// padded with zero-weight lanes to whole vectors of kCellLanes. Returns the padded count.
inline std::size_t gather_cell_candidates(GroupScratch& S, const MlsPass& pass, double rg, const double (&xc)[3],
                                          std::uint16_t body) {
  namespace hn = hwy::HWY_NAMESPACE;
  const hn::ScalableTag<double> d;
  const hn::RebindToSigned<decltype(d)> di;
  const std::size_t N = hn::Lanes(d);
  const ParticleStore& P = *pass.particles;
  const GridGeometry& grid = *pass.grid;
  ParticleBox box;  // the centre alone
  for (int k = 0; k < 3; ++k) box.lo[k] = box.hi[k] = grid.to_grid(k, xc[k]);
  const double keep2 = pass.radius * pass.radius * (1.0 + 1e-9);
  const double* field[9] = {P.x[0].data(), P.x[1].data(), P.x[2].data(), pass.in[0], pass.in[1],
                            pass.in[2],    pass.in[3],    pass.in[4],    pass.in[5]};
  const std::uint16_t* pbody = P.body.data();
  using V = hn::Vec<decltype(d)>;
  const V c0 = hn::Set(d, xc[0]), c1 = hn::Set(d, xc[1]), c2 = hn::Set(d, xc[2]), keep = hn::Set(d, keep2);
  std::size_t nk = 0, nc = 0;
  for_each_candidate_range(pass, box, rg, [&](std::uint32_t q0, std::uint32_t q1) {
    const std::size_t need = nk + (q1 - q0) + N;
    if (S.idx.size() < need) S.idx.resize(std::max(need, 2 * S.idx.size()));
    std::uint32_t q = q0;
    for (; q + N <= q1; q += N) {
      const V x = hn::LoadU(d, field[0] + q), y = hn::LoadU(d, field[1] + q), z = hn::LoadU(d, field[2] + q);
      const V dx = hn::Sub(x, c0), dy = hn::Sub(y, c1), dz = hn::Sub(z, c2);
      const V r2 = hn::Add(hn::Add(hn::Mul(dx, dx), hn::Mul(dy, dy)), hn::Mul(dz, dz));
      // false for a non-finite position; the indices kept (about 1 in 6 at a radius of 1 cell)
      const auto m = hn::RebindMask(di, hn::Lt(r2, keep));
      nk += store_kept_indices(di, m, static_cast<std::int64_t>(q), S.idx.data() + nk);
    }
    for (; q < q1; ++q) {
      const double dx = field[0][q] - xc[0], dy = field[1][q] - xc[1], dz = field[2][q] - xc[2];
      S.idx[nk] = q;
      nk += dx * dx + dy * dy + dz * dz < keep2 ? 1 : 0;
    }
  });
  // Their fields as columns: one predictable loop (a branch per kept lane mispredicts).
  nc = nk;
  if (S.cand[0].size() < nc + kCellLanes)
    for (auto& column : S.cand) column.resize(std::max(nc + kCellLanes, 2 * column.size()));
  for (std::size_t J = 0; J < nc; ++J) {
    const std::int64_t q = S.idx[J];
    for (int k = 0; k < 9; ++k) S.cand[k][J] = field[k][q];
    S.cand[9][J] = pbody[q] == body ? 1.0 : 0.0;
  }
  const std::size_t padded = (nc + kCellLanes - 1) / kCellLanes * kCellLanes;
  for (std::size_t J = nc; J < padded; ++J) {
    for (int k = 0; k < 3; ++k) S.cand[k][J] = xc[k];
    for (int k = 3; k < 10; ++k) S.cand[k][J] = 0.0;
  }
  return padded;
}

/// Fit the particles [p_begin, p_end) of one cell that belong to `body` (of a smoothed body, at
/// finite positions: the caller's `fits`) with one fit centred at the cell's centre xc.
template <int Degree, int Axes>
void smooth_cell(GroupScratch& S, const MlsPass& pass, double rg, const double (&xc)[3], std::uint16_t body,
                 std::uint32_t p_begin, std::uint32_t p_end, const std::uint8_t* fits, std::size_t& smoothed,
                 std::size_t& unsmoothed) {
  constexpr int T = mls_term_count(Degree, Axes);
  constexpr int NA = T * (T + 1) / 2;  // upper triangle of A
  const ParticleStore& P = *pass.particles;
  const std::size_t padded = gather_cell_candidates(S, pass, rg, xc, body);
  const double inv_radius = 1.0 / pass.radius;
  const CellLanes zero = {};
  CellLanes acc[NA], rhs[T][6], count = zero;  // zeroed one by one (an aggregate = {} becomes a slow rep stos)
  for (int k = 0; k < NA; ++k) acc[k] = zero;
  for (int r = 0; r < T; ++r)
    for (int c = 0; c < 6; ++c) rhs[r][c] = zero;
  const double* cand[10];
  for (int k = 0; k < 10; ++k) cand[k] = S.cand[k].data();
  for (std::size_t I0 = 0; I0 < padded; I0 += kCellLanes) {
    CellLanes f[10];
    for (int k = 0; k < 10; ++k) std::memcpy(&f[k], cand[k] + I0, sizeof(CellLanes));
    const CellLanes d0 = (f[0] - xc[0]) * inv_radius, d1 = (f[1] - xc[1]) * inv_radius,
                    d2 = (f[2] - xc[2]) * inv_radius;
    const CellLanes r2 = d0 * d0 + d1 * d1 + d2 * d2;
    const auto in = (r2 < 1.0) & (f[9] != 0.0);
    const CellLanes s = sqrt_lanes(in ? r2 : zero);
    const CellLanes w = in ? weight_inside(s) : zero;  // Edo & Matsubara 2015, eq. 39
    CellLanes u[Axes];  // finite: the candidates have finite positions
    if constexpr (Axes == 3) {
      u[0] = d0, u[1] = d1, u[2] = d2;
    } else {
      const CellLanes dd[3] = {d0, d1, d2};
      for (int ax = 0; ax < Axes; ++ax) u[ax] = dd[pass.axes[ax]];
    }
    count += in ? zero + 1.0 : zero;
    CellLanes F[T], WF[T];
    mls_basis<Degree, Axes>(u, F);
    for (int r = 0; r < T; ++r) WF[r] = w * F[r];
    int k = 0;
    for (int r = 0; r < T; ++r)
      for (int c = r; c < T; ++c, ++k) acc[k] += WF[r] * F[c];  // eq. 42
    for (int c = 0; c < 6; ++c) {
      const CellLanes ec = in ? f[3 + c] : zero;  // a non-finite increment outside the ball stays out
      for (int r = 0; r < T; ++r) rhs[r][c] += WF[r] * ec;
    }
  }
  double A[T][T], Ainv[T][T], B[T][6], C[T][6];
  int k = 0;
  for (int r = 0; r < T; ++r)
    for (int c = r; c < T; ++c, ++k) A[r][c] = A[c][r] = lane_total(acc[k]);
  const bool ok = lane_total(count) >= T && mls_detail::invert_fit<T>(A, pass.min_rcond, Ainv);  // the guard
  if (ok) {
    for (int r = 0; r < T; ++r)
      for (int c = 0; c < 6; ++c) B[r][c] = lane_total(rhs[r][c]);
    for (int r = 0; r < T; ++r)
      for (int c = 0; c < 6; ++c) {
        double v = Ainv[r][0] * B[0][c];
        for (int t = 1; t < T; ++t) v += Ainv[r][t] * B[t][c];
        C[r][c] = v;
      }
  }
  for (std::uint32_t q = p_begin; q < p_end; ++q) {
    if (!fits[q - p_begin] || P.body[q] != body) continue;
    if (!ok) {
      for (int c = 0; c < 6; ++c) pass.out[c][q] = pass.in[c][q];
      ++unsmoothed;
      continue;
    }
    double u[Axes], F[T];
    for (int ax = 0; ax < Axes; ++ax) u[ax] = (P.x[pass.axes[ax]][q] - xc[pass.axes[ax]]) * inv_radius;
    mls_basis<Degree, Axes>(u, F);
    for (int c = 0; c < 6; ++c) {
      double v = F[0] * C[0][c];
      for (int r = 1; r < T; ++r) v += F[r] * C[r][c];
      pass.out[c][q] = v;
    }
    ++smoothed;
  }
}

template <int Degree, int Axes>
MlsCounts smooth_cells_impl(const MlsPass& pass) {
  const ParticleStore& P = *pass.particles;
  const CellSort& sort = *pass.sort;
  const GridGeometry& grid = *pass.grid;
  const std::vector<std::uint8_t>& smooth_body = *pass.smooth_body;
  const int bc = sort.block_cells();
  const std::size_t cells_per_block = static_cast<std::size_t>(bc) * bc * bc;
  const std::vector<std::uint32_t>& cell_start = sort.cell_start();
  const mls_detail::WorkUnits work(sort);
  const std::int64_t units = static_cast<std::int64_t>(work.count());
  const double rg = pass.search_radius / grid.h;  // radius in cells
  std::size_t smoothed = 0, unsmoothed = 0;
#pragma omp parallel reduction(+ : smoothed, unsmoothed)
  {
    GroupScratch S;
    std::vector<std::uint8_t> fits;  // per particle of the cell: fitted (smoothed body, finite position)
#pragma omp for schedule(dynamic, 1)
    for (std::int64_t u = 0; u < units; ++u) {
      const double unit_start = pass.unit_seconds ? omp_get_wtime() : 0.0;
      const std::size_t bi = work.block(u);
      const std::array<int, 3> origin = sort.block_origin(bi);
      const std::size_t base = bi * cells_per_block;
      const std::size_t first = work.first_cell(u);
      for (std::size_t l = first; l < first + static_cast<std::size_t>(bc); ++l) {
        const std::uint32_t p_begin = cell_start[base + l], p_end = cell_start[base + l + 1];
        if (p_begin == p_end) continue;
        fits.assign(p_end - p_begin, 0);
        for (std::uint32_t q = p_begin; q < p_end; ++q) {
          if (!smooth_body[P.body[q]]) {  // not smoothed: copied, and nobody's neighbour
            for (int c = 0; c < 6; ++c) pass.out[c][q] = pass.in[c][q];
            continue;
          }
          if (!(std::isfinite(P.x[0][q]) && std::isfinite(P.x[1][q]) && std::isfinite(P.x[2][q]))) {
            for (int c = 0; c < 6; ++c) pass.out[c][q] = pass.in[c][q];  // no neighbours: the guard
            ++unsmoothed;
            continue;
          }
          fits[q - p_begin] = 1;
        }
        // The cell's centre (local cell l = (li bc + lj) bc + lk, as CellSort lays out a block).
        const int cell[3] = {origin[0] + static_cast<int>(l / (bc * bc)), origin[1] + static_cast<int>((l / bc) % bc),
                             origin[2] + static_cast<int>(l % bc)};
        double xc[3];
        for (int d = 0; d < 3; ++d) xc[d] = grid.node_position(d, cell[d]) + 0.5 * grid.h;
        // One fit per body present (almost always one), in the order the bodies first appear.
        std::uint32_t first_fit = p_begin;
        while (first_fit < p_end && !fits[first_fit - p_begin]) ++first_fit;
        bool one_body = true;
        for (std::uint32_t q = first_fit; q < p_end; ++q)
          one_body = one_body && (!fits[q - p_begin] || P.body[q] == P.body[first_fit]);
        if (one_body) {
          if (first_fit < p_end)
            smooth_cell<Degree, Axes>(S, pass, rg, xc, P.body[first_fit], p_begin, p_end, fits.data(), smoothed,
                                      unsmoothed);
          continue;
        }
        for (std::uint32_t q = p_begin; q < p_end; ++q) {
          if (!fits[q - p_begin]) continue;
          bool first = true;
          for (std::uint32_t o = p_begin; o < q && first; ++o) first = !(fits[o - p_begin] && P.body[o] == P.body[q]);
          if (first)
            smooth_cell<Degree, Axes>(S, pass, rg, xc, P.body[q], p_begin, p_end, fits.data(), smoothed, unsmoothed);
        }
      }
      if (pass.unit_seconds) pass.unit_seconds[u] = omp_get_wtime() - unit_start;
    }
  }
  return {smoothed, unsmoothed};
}

}  // namespace

MlsCounts SmoothMls(const mls_detail::MlsPass& pass) {
  // One instantiation per (degree, axes): the inner loops and the factorisation have fixed sizes.
  auto dispatch = [&]<int Degree>() {
    switch (pass.axis_count) {
      case 1: return pass.cell_fit ? smooth_cells_impl<Degree, 1>(pass) : smooth_impl<Degree, 1>(pass);
      case 2: return pass.cell_fit ? smooth_cells_impl<Degree, 2>(pass) : smooth_impl<Degree, 2>(pass);
      default: return pass.cell_fit ? smooth_cells_impl<Degree, 3>(pass) : smooth_impl<Degree, 3>(pass);
    }
  };
  switch (pass.degree) {
    case 1: return dispatch.template operator()<1>();
    case 2: return dispatch.template operator()<2>();
    default: return dispatch.template operator()<3>();
  }
}

}  // namespace HWY_NAMESPACE
}  // namespace talus
HWY_AFTER_NAMESPACE();

#if HWY_ONCE
namespace talus {

HWY_EXPORT(SmoothMls);

const char* to_string(MlsBasis basis) {
  switch (basis) {
    case MlsBasis::Linear: return "linear";
    case MlsBasis::Quadratic: return "quadratic";
    case MlsBasis::Cubic: return "cubic";
  }
  return "?";
}

const char* to_string(MlsVariant variant) { return variant == MlsVariant::Cell ? "cell" : "particle"; }

MlsStrainSmoother::MlsStrainSmoother(const MlsSettings& settings, double cell_size)
    : settings_(settings), radius_(settings.radius_factor * cell_size) {
  axis_count_ = 0;
  for (int d = 0; d < 3; ++d)
    if (settings_.axes[d]) axis_list_[axis_count_++] = d;
  if (axis_count_ == 0) throw input_error("MLS smoothing needs at least one axis");
  if (!(radius_ > 0.0)) throw input_error(fmt::format("MLS radius {} must be positive", radius_));
}

std::vector<std::uint32_t> MlsStrainSmoother::work_unit_particles(const CellSort& sort) {
  const mls_detail::WorkUnits work(sort);
  const std::size_t cells_per_block = work.columns * work.bc;
  std::vector<std::uint32_t> particles(work.count());
  for (std::size_t u = 0; u < particles.size(); ++u) {
    const std::size_t first = work.block(static_cast<std::int64_t>(u)) * cells_per_block + work.first_cell(static_cast<std::int64_t>(u));
    particles[u] = sort.cell_start()[first + work.bc] - sort.cell_start()[first];
  }
  return particles;
}

int MlsStrainSmoother::term_count() const { return mls_term_count(static_cast<int>(settings_.basis), axis_count_); }

// Every particle's result depends only on the inputs and a fixed visiting order, and is written
// only by its own lane: the output is bit-identical for any thread count and on every path.
MlsCounts MlsStrainSmoother::smooth(const ParticleStore& particles, const CellSort& sort, const GridGeometry& grid,
                                    const std::array<const double*, 6>& in, const std::array<double*, 6>& out,
                                    const std::vector<std::uint8_t>& smooth_body, double drift,
                                    std::vector<double>* unit_seconds) const {
  if (!(drift >= 0.0 && std::isfinite(drift))) throw std::invalid_argument("MLS search drift must be finite and >= 0");
  // The margin covers the round-off of the moves the drift sums (an ulp of a position per step).
  const double search_radius = drift > 0.0 ? (radius_ + drift) * (1.0 + 1e-9) : radius_;
  mls_detail::MlsPass pass{&particles, &sort, &grid, in, out, &smooth_body,
                                 static_cast<int>(settings_.basis), axis_count_, axis_list_, radius_,
                                 settings_.min_rcond, settings_.variant == MlsVariant::Cell, search_radius,
                                 nullptr};
  if (unit_seconds) {
    unit_seconds->assign(mls_detail::WorkUnits(sort).count(), 0.0);
    pass.unit_seconds = unit_seconds->data();
  }
  // The `reference` path runs the baseline build of the same code.
  return (vector_kernels_enabled() ? HWY_DYNAMIC_DISPATCH(SmoothMls) : &HWY_STATIC_DISPATCH(SmoothMls))(pass);
}

}  // namespace talus
#endif
