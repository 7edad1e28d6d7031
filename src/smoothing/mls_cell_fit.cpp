// The MLS strain smoother's one-fit-per-cell variant (MlsVariant::Cell; Edo & Matsubara 2015,
// eq. 38-46 centred at the cell), compiled once per instruction set by Highway's foreach_target and
// dispatched at run time (core/simd_dispatch.hpp). The per-particle fit, the reference, is in
// smoothing/mls_strain_smoother.cpp.
//
// One fit per cell and body, centred at the cell's centre x_c: A and the right-hand sides
// B_c = sum_I W_I F(u_I) d_eps_I,c (u_I = (x_I - x_c) / h, the weight centred at x_c), then the
// coefficients C = A^-1 B and, at each of the cell's particles, d_eps_p = F(u_p)^T C (Edo &
// Matsubara 2015, eq. 42-46 with x_c in place of x_p). Only the candidates within the radius of x_c
// are gathered (about 34 at a radius of 1 cell and 8 particles per cell, against the 216 of the
// 27 cells around it), and they run along the lanes: 8 at a time on every path (a vector of 8
// doubles: one AVX-512 register, two AVX2 or four SSE2 registers), each lane keeping its own
// partial sums, which are added in one fixed order at the end. So the sums, and the results, are
// bit-identical on every path and for any thread count.
#undef HWY_TARGET_INCLUDE
#define HWY_TARGET_INCLUDE "smoothing/mls_cell_fit.cpp"
#include <hwy/foreach_target.h>  // IWYU pragma: keep

#include <hwy/highway.h>
#include <omp.h>

#include "smoothing/mls_pass.hpp"
#include "smoothing/mls_search-inl.h"
#include "talus/core/simd_dispatch.hpp"

#include <algorithm>
#include <cmath>
#include <cstring>
#include <vector>

// Lane vectors live only inside this file's inlined functions: no call passes one by value.
#pragma GCC diagnostic ignored "-Wpsabi"

HWY_BEFORE_NAMESPACE();
namespace talus {
namespace HWY_NAMESPACE {
namespace {

using mls_detail::MlsPass;
using namespace mls_search;

/// Thread-local scratch of one cell's fit. Buffers only grow, so after the first cells a thread
/// allocates nothing.
struct CellScratch {
  std::vector<std::int64_t> idx;  // the store indices of the candidates kept
  std::array<std::vector<double>, 10> cand;  // their x, y, z, six increments and body flag as columns
};

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
inline std::size_t gather_cell_candidates(CellScratch& S, const MlsPass& pass, double rg, const double (&xc)[3],
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
void smooth_cell(CellScratch& S, const MlsPass& pass, double rg, const double (&xc)[3], std::uint16_t body,
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
  const mls_detail::PassCells cells(pass);
  const ParticleStore& P = cells.P;
  const int bc = cells.bc;
  return for_each_work_unit(pass, [&](MlsCounts& counts, auto&& for_units) {
    CellScratch S;
    std::vector<std::uint8_t> fits;  // per particle of the cell: fitted (smoothed body, finite position)
    for_units([&](const mls_detail::WorkUnits& work, std::int64_t u) {
      const std::size_t bi = work.block(u);
      const std::array<int, 3> origin = cells.sort.block_origin(bi);
      const std::size_t base = bi * cells.cells_per_block;
      const std::size_t first = work.first_cell(u);
      for (std::size_t l = first; l < first + static_cast<std::size_t>(bc); ++l) {
        const std::uint32_t p_begin = cells.cell_start[base + l], p_end = cells.cell_start[base + l + 1];
        if (p_begin == p_end) continue;
        fits.assign(p_end - p_begin, 0);
        for (std::uint32_t q = p_begin; q < p_end; ++q) {
          if (!is_fitted(pass, q)) {
            copy_unfitted(pass, q, counts.unsmoothed);
            continue;
          }
          fits[q - p_begin] = 1;
        }
        // The cell's centre (local cell l = (li bc + lj) bc + lk, as CellSort lays out a block).
        const int cell[3] = {origin[0] + static_cast<int>(l / (bc * bc)), origin[1] + static_cast<int>((l / bc) % bc),
                             origin[2] + static_cast<int>(l % bc)};
        double xc[3];
        for (int d = 0; d < 3; ++d) xc[d] = cells.grid.node_position(d, cell[d]) + 0.5 * cells.grid.h;
        // One fit per body present (almost always one), in the order the bodies first appear.
        std::uint32_t first_fit = p_begin;
        while (first_fit < p_end && !fits[first_fit - p_begin]) ++first_fit;
        bool one_body = true;
        for (std::uint32_t q = first_fit; q < p_end; ++q)
          one_body = one_body && (!fits[q - p_begin] || P.body[q] == P.body[first_fit]);
        if (one_body) {
          if (first_fit < p_end)
            smooth_cell<Degree, Axes>(S, pass, cells.rg, xc, P.body[first_fit], p_begin, p_end, fits.data(),
                                      counts.smoothed, counts.unsmoothed);
          continue;
        }
        for (std::uint32_t q = p_begin; q < p_end; ++q) {
          if (!fits[q - p_begin]) continue;
          bool first = true;
          for (std::uint32_t o = p_begin; o < q && first; ++o) first = !(fits[o - p_begin] && P.body[o] == P.body[q]);
          if (first)
            smooth_cell<Degree, Axes>(S, pass, cells.rg, xc, P.body[q], p_begin, p_end, fits.data(), counts.smoothed,
                                      counts.unsmoothed);
        }
      }
    });
  });
}

}  // namespace

MlsCounts SmoothMlsCells(const mls_detail::MlsPass& pass) {
  return with_basis(pass, [&]<int Degree, int Axes>() { return smooth_cells_impl<Degree, Axes>(pass); });
}

}  // namespace HWY_NAMESPACE
}  // namespace talus
HWY_AFTER_NAMESPACE();

#if HWY_ONCE
namespace talus {

HWY_EXPORT(SmoothMlsCells);

MlsCounts mls_detail::smooth_cell_fits(const MlsPass& pass) {
  // The `reference` path runs the baseline build of the same code.
  return (vector_kernels_enabled() ? HWY_DYNAMIC_DISPATCH(SmoothMlsCells) : &HWY_STATIC_DISPATCH(SmoothMlsCells))(pass);
}

}  // namespace talus
#endif
