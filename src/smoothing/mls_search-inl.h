// The MLS smoother's per-target pieces that its two fits share (smoothing/mls_strain_smoother.cpp
// and smoothing/mls_cell_fit.cpp include this once per Highway target): the choice of a compiled
// basis (with_basis), the loop over the work units (for_each_work_unit), which particles are fitted (is_fitted, copy_unfitted), the eq. 39 weight and
// the square root on lanes, the search's walk over the cells near a box, and the compacting store
// of the kept candidates' indices.

// Highway's per-target include guard: foreach_target includes this once for each target.
#if defined(TALUS_MLS_SEARCH_INL_H_) == defined(HWY_TARGET_TOGGLE)
#ifdef TALUS_MLS_SEARCH_INL_H_
#undef TALUS_MLS_SEARCH_INL_H_
#else
#define TALUS_MLS_SEARCH_INL_H_
#endif

#include <hwy/highway.h>
#include <omp.h>

#include "smoothing/mls_pass.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <vector>

HWY_BEFORE_NAMESPACE();
namespace talus {
namespace HWY_NAMESPACE {
namespace mls_search {

using mls_detail::MlsPass;

/// impl.template operator()<Degree, Axes>() for the pass's basis: one instantiation per (degree,
/// axes), so that the inner loops and the factorisation have fixed sizes.
template <class Impl>
MlsCounts with_basis(const MlsPass& pass, Impl&& impl) {
  auto with_axes = [&]<int Degree>() {
    switch (pass.axis_count) {
      case 1: return impl.template operator()<Degree, 1>();
      case 2: return impl.template operator()<Degree, 2>();
      default: return impl.template operator()<Degree, 3>();
    }
  };
  switch (pass.degree) {
    case 1: return with_axes.template operator()<1>();
    case 2: return with_axes.template operator()<2>();
    default: return with_axes.template operator()<3>();
  }
}

/// Both fits' loop over the work units (mls_detail::WorkUnits): one parallel region, in which
/// thread(counts, for_units) runs once per thread with scratch of its own; for_units(fit_unit) hands
/// the thread units one at a time (`schedule(dynamic, 1)`, the sort's work order) and calls
/// fit_unit(work, u) for each, timing it into pass.unit_seconds when asked. The counts the threads
/// add up are summed.
template <class Thread>
MlsCounts for_each_work_unit(const MlsPass& pass, Thread&& thread) {
  const mls_detail::WorkUnits work(*pass.sort);
  const std::int64_t units = static_cast<std::int64_t>(work.count());
  std::size_t smoothed = 0, unsmoothed = 0;
#pragma omp parallel reduction(+ : smoothed, unsmoothed)
  {
    MlsCounts counts;
    thread(counts, [&](auto&& fit_unit) {
#pragma omp for schedule(dynamic, 1)
      for (std::int64_t u = 0; u < units; ++u) {
        const double unit_start = pass.unit_seconds ? omp_get_wtime() : 0.0;
        fit_unit(work, u);
        if (pass.unit_seconds) pass.unit_seconds[u] = omp_get_wtime() - unit_start;
      }
    });
    smoothed += counts.smoothed;
    unsmoothed += counts.unsmoothed;
  }
  return {smoothed, unsmoothed};
}

/// Whether particle q is fitted: of a smoothed body, at a finite position. Otherwise
/// copy_unfitted() passes its increment on unchanged.
inline bool is_fitted(const MlsPass& pass, std::uint32_t q) {
  const ParticleStore& P = *pass.particles;
  return (*pass.smooth_body)[P.body[q]] && std::isfinite(P.x[0][q]) && std::isfinite(P.x[1][q]) &&
         std::isfinite(P.x[2][q]);
}

/// The increment of a particle that is not fitted, copied unchanged: one of a body not smoothed
/// (nobody's neighbour either), or one at a non-finite position, which has no neighbours; the guard
/// counts the latter in `unsmoothed`.
inline void copy_unfitted(const MlsPass& pass, std::uint32_t q, std::size_t& unsmoothed) {
  for (int c = 0; c < 6; ++c) pass.out[c][q] = pass.in[c][q];
  if ((*pass.smooth_body)[pass.particles->body[q]]) ++unsmoothed;
}

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

/// The box of the group's particles, in grid coordinates (the search) and in metres (the
/// candidate filter). The box, not the cell, bounds the search, so a particle off its sorted cell
/// still finds all its neighbours.
struct ParticleBox {
  double lo[3] = {HUGE_VAL, HUGE_VAL, HUGE_VAL}, hi[3] = {-HUGE_VAL, -HUGE_VAL, -HUGE_VAL};
  double xlo[3] = {HUGE_VAL, HUGE_VAL, HUGE_VAL}, xhi[3] = {-HUGE_VAL, -HUGE_VAL, -HUGE_VAL};
};

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
}  // namespace mls_search
}  // namespace HWY_NAMESPACE
}  // namespace talus
HWY_AFTER_NAMESPACE();

#endif  // TALUS_MLS_SEARCH_INL_H_
