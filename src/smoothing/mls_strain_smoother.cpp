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
//
// The one-fit-per-cell variant is in smoothing/mls_cell_fit.cpp; what both share is in
// smoothing/mls_pass.hpp (compiled once) and smoothing/mls_search-inl.h (per target).
#undef HWY_TARGET_INCLUDE
#define HWY_TARGET_INCLUDE "smoothing/mls_strain_smoother.cpp"
#include <hwy/foreach_target.h>  // IWYU pragma: keep

#include <hwy/aligned_allocator.h>
#include <hwy/highway.h>
#include <omp.h>

#include "smoothing/mls_pass.hpp"
#include "smoothing/mls_search-inl.h"
#include "talus/core/error.hpp"
#include "talus/core/simd_dispatch.hpp"
#include "talus/smoothing/mls_strain_smoother.hpp"

#include <fmt/core.h>

#include <algorithm>
#include <cmath>
#include <stdexcept>
#include <vector>

// Lane vectors live only inside this file's inlined functions: no call passes one by value.
#pragma GCC diagnostic ignored "-Wpsabi"

HWY_BEFORE_NAMESPACE();
namespace talus {
namespace HWY_NAMESPACE {
namespace {

using mls_detail::MlsPass;
using namespace mls_search;

// Particles fitted together, one per lane: one vector register of doubles (8 with AVX-512, 4
// with AVX2, 2 on the baseline), so that A's sums stay in registers. A particle's result does not
// depend on its group, so the paths agree although their groups differ.
constexpr int kGroup = HWY_LANES(double) > 2 ? HWY_LANES(double) : 2;
typedef double Lanes __attribute__((vector_size(kGroup * sizeof(double)), may_alias));

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
  // pass 2), and their Phi when the weights are kept: 5 x kGroup doubles, aligned for whole-vector
  // loads.
  hwy::AlignedFreeUniquePtr<double[]> lanes;
  std::size_t lanes_capacity = 0;  // candidates
  int thread = 0;                  // omp_get_thread_num(), for the weight recorder
  Lanes* lane_array(int k) { return reinterpret_cast<Lanes*>(lanes.get()) + k * lanes_capacity; }
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
/// I, W_I = 0 outside the lane's ball or body; each lane then solves a = A^-1 e_0 (eq. 46, the
/// guard); pass 2 sums d_eps_p = sum_I W_I (a^T F(u_I)) d_eps_I (eq. 45, a^T B d_eps per candidate).
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
    S.lanes = hwy::AllocateAligned<double>(5 * kGroup * S.lanes_capacity);
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
  // Pass 2: Phi_I = W_I a^T F(u_I) (eq. 46) times the candidates' increments (eq. 45).
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
  Lanes* const kept_phi = pass.record ? S.lane_array(4) : nullptr;
  for (std::size_t I = 0; I < nc; ++I) {
    const Lanes phi = phi_of(I);
    if (kept_phi) kept_phi[I] = phi;
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
  // The `reused` variant keeps each fitted lane's neighbours (W_I > 0: inside its ball and body)
  // and their Phi, in the candidates' order: the terms of its sums that are not zeros.
  // (Written without a branch: a candidate is written at the next place, which advances when W > 0.)
  if (kept_phi)
    for (int v = 0; v < n; ++v)
      if (ok[v])
        pass.record->add(S.thread, p[v], nc, [&](std::uint32_t* neighbour, double* phi) {
          std::size_t k = 0;
          for (std::size_t I = 0; I < nc; ++I) {
            neighbour[k] = static_cast<std::uint32_t>(idx[I]);
            phi[k] = kept_phi[I][v];
            k += ww[I][v] != 0.0 ? 1 : 0;
          }
          return k;
        });
  for (int v = 0; v < n; ++v) {
    const std::uint32_t q = p[v];
    for (int c = 0; c < 6; ++c) pass.out[c][q] = ok[v] ? sum[c][v] : pass.in[c][q];  // the guard: unsmoothed
    smoothed += ok[v] ? 1 : 0;
    unsmoothed += ok[v] ? 0 : 1;
  }
}

template <int Degree, int Axes>
MlsCounts smooth_impl(const MlsPass& pass) {
  const mls_detail::PassCells cells(pass);
  return for_each_work_unit(pass, [&](MlsCounts& counts, auto&& for_units) {
    GroupScratch S;
    S.thread = omp_get_thread_num();
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
    auto flush = [&] {
      if (n == 0) return;
      if (range_begin != gathered_begin || range_end != gathered_end) {
        ParticleBox box;
        fittable_in_range = 0;
        for (std::uint32_t q = range_begin; q < range_end; ++q) {
          if (!is_fitted(pass, q)) continue;
          ++fittable_in_range;
          for (int d = 0; d < 3; ++d) {
            const double x = cells.P.x[d][q], xg = cells.grid.to_grid(d, x);
            box.lo[d] = xg < box.lo[d] ? xg : box.lo[d];
            box.hi[d] = xg > box.hi[d] ? xg : box.hi[d];
            box.xlo[d] = x < box.xlo[d] ? x : box.xlo[d];
            box.xhi[d] = x > box.xhi[d] ? x : box.xhi[d];
          }
        }
        nc = gather_candidates(S, pass, box, cells.rg);
        S.idx_x_current = false;
        gathered_begin = range_begin;
        gathered_end = range_end;
      }
      // A group of every fittable particle of its cells (one group per cell on AVX-512) has the
      // gathered box as its own: the gathered list is its list.
      if (static_cast<std::size_t>(n) == fittable_in_range) {
        smooth_group<Degree, Axes>(S, S.idx.data(), nc, pass, group, n, counts.smoothed, counts.unsmoothed);
        n = 0;
        return;
      }
      // The group's own box keeps its list short: the candidates within the radius of it, in the
      // cells' order, are those a search from the group's box alone would find, in its order.
      double xlo[3] = {HUGE_VAL, HUGE_VAL, HUGE_VAL}, xhi[3] = {-HUGE_VAL, -HUGE_VAL, -HUGE_VAL};
      for (int g = 0; g < n; ++g)
        for (int d = 0; d < 3; ++d) {
          const double x = cells.P.x[d][group[g]];
          xlo[d] = x < xlo[d] ? x : xlo[d];
          xhi[d] = x > xhi[d] ? x : xhi[d];
        }
      const std::size_t ng = filter_for_group(S, cells.P, nc, xlo, xhi, keep2);
      smooth_group<Degree, Axes>(S, S.group_idx.data(), ng, pass, group, n, counts.smoothed, counts.unsmoothed);
      n = 0;
    };
    for_units([&](const mls_detail::WorkUnits& work, std::int64_t u) {
      // Groups: up to kGroup particles from consecutive cells of one column along k (their box
      // stays about one cell wide); a cell joins the open group only if all of it fits. A group
      // never spans two columns (it is flushed at the end of each).
      const std::size_t base = work.block(u) * cells.cells_per_block + work.first_cell(u);
      for (std::size_t l = 0; l < static_cast<std::size_t>(cells.bc); ++l) {
        const std::uint32_t p_begin = cells.cell_start[base + l], p_end = cells.cell_start[base + l + 1];
        if (p_begin == p_end) continue;
        if (n > 0 && (static_cast<std::uint32_t>(n) + (p_end - p_begin) > kGroup || l == 0 ||
                      cells.cell_start[base + l - 1] == cells.cell_start[base + l]))
          flush();
        for (std::uint32_t q = p_begin; q < p_end; ++q) {
          if (!is_fitted(pass, q)) {
            copy_unfitted(pass, q, counts.unsmoothed);
            continue;
          }
          if (n == kGroup) flush();
          if (n == 0) range_begin = p_begin;
          range_end = p_end;
          group[n++] = q;
        }
      }
      flush();
    });
  });
}

}  // namespace

MlsCounts SmoothMls(const mls_detail::MlsPass& pass) {
  return with_basis(pass, [&]<int Degree, int Axes>() { return smooth_impl<Degree, Axes>(pass); });
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

const char* to_string(MlsVariant variant) {
  switch (variant) {
    case MlsVariant::Particle: return "particle";
    case MlsVariant::Cell: return "cell";
    case MlsVariant::Reused: return "reused";
  }
  return "?";
}

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
                                    std::vector<double>* unit_seconds, MlsStoredWeights* keep) const {
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
  if (pass.cell_fit) {
    if (keep) throw std::invalid_argument("MLS: the one-fit-per-cell variant keeps no weights");
    return mls_detail::smooth_cell_fits(pass);
  }
  if (keep) {
    keep->begin_fit(particles.size(), omp_get_max_threads());
    pass.record = keep;
  }
  // The `reference` path runs the baseline build of the same code.
  const MlsCounts counts =
      (vector_kernels_enabled() ? HWY_DYNAMIC_DISPATCH(SmoothMls) : &HWY_STATIC_DISPATCH(SmoothMls))(pass);
  if (keep) keep->end_fit();
  return counts;
}

}  // namespace talus
#endif
