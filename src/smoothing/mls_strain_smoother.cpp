#include "talus/smoothing/mls_strain_smoother.hpp"

#include "talus/core/error.hpp"

#include <Eigen/Cholesky>
#include <Eigen/Core>
#include <fmt/core.h>

#include <algorithm>
#include <cmath>
#include <vector>

namespace talus {

const char* to_string(MlsBasis basis) {
  switch (basis) {
    case MlsBasis::Linear: return "linear";
    case MlsBasis::Quadratic: return "quadratic";
    case MlsBasis::Cubic: return "cubic";
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

int MlsStrainSmoother::term_count() const { return mls_term_count(static_cast<int>(settings_.basis), axis_count_); }

MlsCounts MlsStrainSmoother::smooth(const ParticleStore& particles, const CellSort& sort, const GridGeometry& grid,
                                    const std::array<const double*, 6>& in, const std::array<double*, 6>& out,
                                    const std::vector<std::uint8_t>& smooth_body) const {
  // One instantiation per (degree, axes): the inner loops and the factorisation have fixed sizes.
  auto dispatch = [&]<int Degree>() {
    switch (axis_count_) {
      case 1: return smooth_with<Degree, 1>(particles, sort, grid, in, out, smooth_body);
      case 2: return smooth_with<Degree, 2>(particles, sort, grid, in, out, smooth_body);
      default: return smooth_with<Degree, 3>(particles, sort, grid, in, out, smooth_body);
    }
  };
  switch (settings_.basis) {
    case MlsBasis::Linear: return dispatch.template operator()<1>();
    case MlsBasis::Quadratic: return dispatch.template operator()<2>();
    case MlsBasis::Cubic: return dispatch.template operator()<3>();
  }
  return {};
}

namespace {

/// Distance (in cells) from the grid-coordinate interval [lo, hi] to the cell [i, i + 1). With
/// lo = hi = x this is the distance from the point x; it only shrinks as [lo, hi] grows.
inline double gap_to_cell(int i, double lo, double hi) {
  const double a = i - hi, b = lo - (i + 1);
  const double g = a > b ? a : b;
  return g > 0.0 ? g : 0.0;
}

/// Cubic spline of Edo & Matsubara 2015, eq. 39 for 0 <= s < 1, the same arithmetic as mls_weight but as one
/// select, so the loop over neighbours vectorises (callers pass s < 1 only, or zero-weight padding).
inline double mls_weight_inside(double s) {
  const double inner = 2.0 / 3.0 - 4.0 * s * s + 4.0 * s * s * s;
  const double outer = 4.0 / 3.0 - 4.0 * s + 4.0 * s * s - 4.0 / 3.0 * s * s * s;
  return s < 0.5 ? inner : outer;
}

/// Thread-local scratch: the candidate particles of one cell, and the neighbours of one particle.
/// Vectors only grow, so after the first cells a thread allocates nothing.
struct MlsScratch {
  // Candidates: every particle in the cells that meet the ball around any particle of the cell.
  std::vector<double> cx[3], cbody;
  std::vector<std::uint32_t> cq;  // store index
  std::vector<double> s2;         // squared scaled distance to the current particle (2 for other bodies)
  // Neighbours of the current particle, compacted, padded with zero weights to a multiple of kLanes.
  std::vector<std::uint32_t> nb;  // candidate index
  std::vector<double> u[3], w;
};

constexpr int kLanes = 2;  // neighbours per step of the accumulation loops (10 SSE2 accumulators for linear)

/// The fit's solve for a well-conditioned A (the common case), in plain fixed-size loops that the
/// compiler unrolls: Cholesky A = L L^T, then A^-1 = L^-T L^-1 explicitly, a = A^-1 e_0 its first
/// column, and the exact reciprocal condition number 1 / (|A|_1 |A^-1|_1). Eigen's rcond() is an
/// estimate of the same quantity from below for |A^-1|_1, so it is never smaller than the exact
/// value: when the exact one clears 2 * min_rcond (the factor 2 absorbs round-off in A^-1), the
/// guard passes for certain. Returns false otherwise (not positive definite, or ill-conditioned,
/// or not finite): the caller then decides with Eigen's LLT and rcond() as before.
template <int T>
bool solve_well_conditioned(const double (&A)[T][T], double min_rcond, double (&a)[T]) {
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
      sa += std::abs(A[r][c]);
      si += std::abs(v);
    }
    a_norm = sa > a_norm ? sa : a_norm;
    ainv_norm = si > ainv_norm ? si : ainv_norm;
  }
  return a_norm * ainv_norm * (2.0 * min_rcond) <= 1.0;  // false for NaN or inf
}

/// The box of a cell's particles to smooth, in grid coordinates (the search) and in metres (the
/// candidate filter). The box, not the cell, bounds the search, so a particle off its sorted cell
/// still finds all its neighbours.
struct ParticleBox {
  double lo[3] = {HUGE_VAL, HUGE_VAL, HUGE_VAL}, hi[3] = {-HUGE_VAL, -HUGE_VAL, -HUGE_VAL};
  double xlo[3] = {HUGE_VAL, HUGE_VAL, HUGE_VAL}, xhi[3] = {-HUGE_VAL, -HUGE_VAL, -HUGE_VAL};
  bool empty() const { return !(lo[0] <= hi[0]); }
};

/// The box of the cell's particles [p_begin, p_end) of smoothed bodies; the others are copied.
[[gnu::always_inline]] inline ParticleBox box_and_copy_unsmoothed(const ParticleStore& P, const GridGeometry& grid,
                                                                  std::uint32_t p_begin, std::uint32_t p_end,
                                                                  const std::vector<std::uint8_t>& smooth_body,
                                                                  const std::array<const double*, 6>& in,
                                                                  const std::array<double*, 6>& out) {
  ParticleBox box;
  for (std::uint32_t p = p_begin; p < p_end; ++p) {
    if (!smooth_body[P.body[p]]) {
      for (int c = 0; c < 6; ++c) out[c][p] = in[c][p];
      continue;
    }
    for (int d = 0; d < 3; ++d) {
      const double x = P.x[d][p], xg = grid.to_grid(d, x);
      box.lo[d] = xg < box.lo[d] ? xg : box.lo[d];
      box.hi[d] = xg > box.hi[d] ? xg : box.hi[d];
      box.xlo[d] = x < box.xlo[d] ? x : box.xlo[d];
      box.xhi[d] = x > box.xhi[d] ? x : box.xhi[d];
    }
  }
  return box;
}

/// Append the particles [q0, q1) to the candidates (positions, bodies, store indices).
[[gnu::always_inline]] inline void append_candidates(MlsScratch& S, std::size_t& nc, const ParticleStore& P,
                                                     std::uint32_t q0, std::uint32_t q1) {
  const std::size_t need = nc + (q1 - q0);
  if (S.cq.size() < need) {
    const std::size_t cap = std::max<std::size_t>(need, 2 * S.cq.size());
    for (int d = 0; d < 3; ++d) S.cx[d].resize(cap);
    S.cbody.resize(cap);
    S.cq.resize(cap);
  }
  for (std::uint32_t q = q0; q < q1; ++q, ++nc) {
    for (int d = 0; d < 3; ++d) S.cx[d][nc] = P.x[d][q];
    S.cbody[nc] = P.body[q];
    S.cq[nc] = q;
  }
}

/// Gather, into S, the particles of the cells that meet the ball of radius rg (cells) around any
/// point of the box: the same walk as for a single particle (lo = hi), so each particle's own
/// search is a subset. Along k the cells of one block are contiguous in the store: one range per
/// block. Returns the candidate count.
[[gnu::always_inline]] inline std::size_t gather_candidates(MlsScratch& S, const ParticleStore& P, const CellSort& sort,
                                                            const ParticleBox& box, double rg) {
  const int bc = sort.block_cells();
  const std::size_t cells_per_block = static_cast<std::size_t>(bc) * bc * bc;
  const std::vector<std::uint32_t>& cell_start = sort.cell_start();
  const double rg2 = rg * rg;
  const int reach = static_cast<int>(std::ceil(rg));
  std::size_t nc = 0;
  const int i0 = static_cast<int>(std::floor(box.lo[0])), i1 = static_cast<int>(std::floor(box.hi[0]));
  const int j0 = static_cast<int>(std::floor(box.lo[1])), j1 = static_cast<int>(std::floor(box.hi[1]));
  for (int i = std::max(0, i0 - reach); i <= i1 + reach; ++i) {
    const double gi = gap_to_cell(i, box.lo[0], box.hi[0]);
    if (gi * gi >= rg2) continue;
    for (int j = std::max(0, j0 - reach); j <= j1 + reach; ++j) {
      const double gj = gap_to_cell(j, box.lo[1], box.hi[1]);
      const double rem = rg2 - gi * gi - gj * gj;
      if (rem <= 0.0) continue;
      const double half = std::sqrt(rem);
      int k = std::max(0, static_cast<int>(std::floor(box.lo[2] - half)));
      const int k_last = static_cast<int>(std::floor(box.hi[2] + half));
      while (k <= k_last) {
        const int k_end = std::min(k_last, (k / bc) * bc + bc - 1);  // last cell of this block along k
        const long long cb = sort.active_block_of_cell(i, j, k);
        if (cb >= 0) {
          // Local cell within the block: the block's origin is the cell index rounded down to a
          // multiple of bc (cheaper than CellSort::block_origin's divisions).
          const std::size_t cbase = static_cast<std::size_t>(cb) * cells_per_block;
          const std::size_t l0 = static_cast<std::size_t>(((i % bc) * bc + (j % bc)) * bc + (k % bc));
          const std::size_t l1 = l0 + static_cast<std::size_t>(k_end - k);
          append_candidates(S, nc, P, cell_start[cbase + l0], cell_start[cbase + l1 + 1]);
        }
        k = k_end + 1;
      }
    }
  }
  return nc;
}

/// Keep only the candidates within the radius of the particles' box [xlo, xhi]: the others are
/// nobody's neighbour here. The cells gathered hold about twice as many as the ball around the box
/// (radius 1 cell), and every particle would test them all. The margin keeps a candidate at the
/// radius within round-off; the exact test per particle decides, so the neighbours (and their
/// order) are unchanged. Returns the new candidate count.
[[gnu::always_inline]] inline std::size_t keep_near_box(MlsScratch& S, std::size_t nc, const ParticleBox& box,
                                                        double radius) {
  const double keep2 = radius * radius * (1.0 + 1e-9);
  std::size_t kept = 0;
  for (std::size_t I = 0; I < nc; ++I) {
    double g2 = 0.0;
    for (int d = 0; d < 3; ++d) {
      const double x = S.cx[d][I];
      const double below = box.xlo[d] - x, above = x - box.xhi[d];
      const double gap = below > above ? below : above;
      g2 += gap > 0.0 ? gap * gap : 0.0;
    }
    for (int d = 0; d < 3; ++d) S.cx[d][kept] = S.cx[d][I];
    S.cbody[kept] = S.cbody[I];
    S.cq[kept] = S.cq[I];
    kept += g2 < keep2 ? 1 : 0;
  }
  // the per-particle buffers hold every candidate, padded to whole steps of kLanes
  if (S.s2.size() < kept) {
    S.s2.resize(S.cq.size());
    S.nb.resize(S.cq.size() + kLanes);
    for (int d = 0; d < 3; ++d) S.u[d].resize(S.cq.size() + kLanes);
    S.w.resize(S.cq.size() + kLanes);
  }
  return kept;
}

/// The neighbours of the particle at xp among the nc candidates: their candidate indices (S.nb),
/// scaled offsets along the basis axes (S.u) and eq. 39 weights (S.w), padded with zero weights to
/// whole steps of kLanes (their terms add exactly zero). Strain is discontinuous across bodies, so
/// another body's particle is never a neighbour (the usual case, candidates of one body only, skips
/// that test). Returns the neighbour count m; the padded count is m rounded up to kLanes.
template <int Axes>
[[gnu::always_inline]] inline std::size_t find_neighbours(MlsScratch& S, std::size_t nc, const double (&xp)[3],
                                                          double bodyd, bool one_body, double inv_radius,
                                                          const std::array<int, 3>& axes) {
  const double* cx[3] = {S.cx[0].data(), S.cx[1].data(), S.cx[2].data()};
  const double *cx0 = cx[0], *cx1 = cx[1], *cx2 = cx[2];
  const double* cbody = S.cbody.data();
  const double xp0 = xp[0], xp1 = xp[1], xp2 = xp[2];
  double* s2 = S.s2.data();
  std::uint32_t* nb = S.nb.data();
  double* u[3] = {S.u[0].data(), S.u[1].data(), S.u[2].data()};
  double* w = S.w.data();
  // Distance test over all candidates (vectorised).
  if (one_body) {
#pragma omp simd
    for (std::size_t I = 0; I < nc; ++I) {
      const double d0 = (cx0[I] - xp0) * inv_radius, d1 = (cx1[I] - xp1) * inv_radius, d2 = (cx2[I] - xp2) * inv_radius;
      s2[I] = d0 * d0 + d1 * d1 + d2 * d2;
    }
  } else {
#pragma omp simd
    for (std::size_t I = 0; I < nc; ++I) {
      const double d0 = (cx0[I] - xp0) * inv_radius, d1 = (cx1[I] - xp1) * inv_radius, d2 = (cx2[I] - xp2) * inv_radius;
      const double r2 = d0 * d0 + d1 * d1 + d2 * d2;
      s2[I] = cbody[I] == bodyd ? r2 : 2.0;
    }
  }
  // Compact the neighbours (s < 1) without branches.
  std::size_t m = 0;
  for (std::size_t I = 0; I < nc; ++I) {
    nb[m] = static_cast<std::uint32_t>(I);
    m += s2[I] < 1.0 ? 1 : 0;
  }
  // u holds only the axes the basis spans, in order.
  for (std::size_t k = 0; k < m; ++k) {
    const std::uint32_t I = nb[k];
    for (int ax = 0; ax < Axes; ++ax) u[ax][k] = (cx[axes[ax]][I] - xp[axes[ax]]) * inv_radius;
    w[k] = s2[I];
  }
  const std::size_t m_pad = (m + kLanes - 1) / kLanes * kLanes;
  for (std::size_t k = m; k < m_pad; ++k) {
    for (int ax = 0; ax < Axes; ++ax) u[ax][k] = 0.0;
    w[k] = 1.0;  // s^2 = 1: weight 0
    nb[k] = 0;
  }
#pragma omp simd
  for (std::size_t k = 0; k < m_pad; ++k) {
    const double s = std::sqrt(w[k]);
    w[k] = k < m ? mls_weight_inside(s) : 0.0;  // Edo & Matsubara 2015, eq. 39
  }
  return m;
}

/// The fit's coefficients a = A^-1 F(0), F(0) = e_0 (Edo & Matsubara 2015, eq. 42, 45), for the m
/// neighbours in S (padded to m_pad). False (the guard) with too few neighbours for the basis, or a
/// (nearly) singular A.
template <int Degree, int Axes>
[[gnu::always_inline]] inline bool fit_coefficients(const MlsScratch& S, std::size_t m, std::size_t m_pad,
                                                    double min_rcond, double (&a)[mls_term_count(Degree, Axes)]) {
  constexpr int T = mls_term_count(Degree, Axes);
  constexpr int NA = T * (T + 1) / 2;  // upper triangle of A
  using MatT = Eigen::Matrix<double, T, T>;
  using VecT = Eigen::Matrix<double, T, 1>;
  if (m < static_cast<std::size_t>(T)) return false;
  const double* u[3] = {S.u[0].data(), S.u[1].data(), S.u[2].data()};
  const double* w = S.w.data();
  // A = sum_I W_I F(u_I) F(u_I)^T (eq. 42), upper triangle, kLanes neighbours per step in separate
  // lanes so the loop body vectorises; lanes are summed at the end.
  double acc[NA][kLanes] = {};
  for (std::size_t k0 = 0; k0 < m_pad; k0 += kLanes) {
    double F[T][kLanes], WF[T][kLanes];
    for (int v = 0; v < kLanes; ++v) {
      double uu[Axes], f[T];
      for (int ax = 0; ax < Axes; ++ax) uu[ax] = u[ax][k0 + v];
      mls_basis<Degree, Axes>(uu, f);
      for (int r = 0; r < T; ++r) {
        F[r][v] = f[r];
        WF[r][v] = w[k0 + v] * f[r];
      }
    }
    int e = 0;
    for (int r = 0; r < T; ++r)
      for (int c = r; c < T; ++c, ++e)
        for (int v = 0; v < kLanes; ++v) acc[e][v] += WF[r][v] * F[c][v];
  }
  double A[T][T];
  int e = 0;
  for (int r = 0; r < T; ++r)
    for (int c = r; c < T; ++c, ++e) {
      double sum = 0.0;
      for (int v = 0; v < kLanes; ++v) sum += acc[e][v];
      A[r][c] = A[c][r] = sum;
    }
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

/// The smoothed increment of particle p (Edo & Matsubara 2015, eq. 45-46): Phi_I = W_I a^T F(u_I),
/// d_eps_p = sum_I Phi_I d_eps_I (a^T B d_eps summed per neighbour: one pass of T + 6 products
/// instead of T x 6 sums of B d_eps). a^T F is summed term by term across the lanes, so the lanes
/// vectorise (4 or 8 lanes here measured slower: spills and padding).
template <int Degree, int Axes>
[[gnu::always_inline]] inline void apply_fit(const MlsScratch& S, std::size_t m_pad,
                                             const double (&a)[mls_term_count(Degree, Axes)],
                                             const std::array<const double*, 6>& in,
                                             const std::array<double*, 6>& out, std::uint32_t p) {
  constexpr int T = mls_term_count(Degree, Axes);
  const double* u[3] = {S.u[0].data(), S.u[1].data(), S.u[2].data()};
  const double* w = S.w.data();
  const std::uint32_t* nb = S.nb.data();
  double sum[6][kLanes] = {};
  for (std::size_t k0 = 0; k0 < m_pad; k0 += kLanes) {
    double F[T][kLanes], phi[kLanes] = {};
    for (int v = 0; v < kLanes; ++v) {
      double uu[Axes], f[T];
      for (int ax = 0; ax < Axes; ++ax) uu[ax] = u[ax][k0 + v];
      mls_basis<Degree, Axes>(uu, f);
      for (int r = 0; r < T; ++r) F[r][v] = f[r];
    }
    for (int r = 0; r < T; ++r)
      for (int v = 0; v < kLanes; ++v) phi[v] += a[r] * F[r][v];
    for (int v = 0; v < kLanes; ++v) phi[v] *= w[k0 + v];
    for (int c = 0; c < 6; ++c) {
      const double* ec = in[c];
      for (int v = 0; v < kLanes; ++v) sum[c][v] += phi[v] * ec[S.cq[nb[k0 + v]]];
    }
  }
  for (int c = 0; c < 6; ++c) {
    double total = 0.0;
    for (int v = 0; v < kLanes; ++v) total += sum[c][v];
    out[c][p] = total;
  }
}

}  // namespace

// Work goes cell by cell: the candidates of all particles of a cell are gathered once into a
// contiguous buffer, and each particle then tests them in a loop that vectorises. Every particle's
// result depends only on the inputs and a fixed visiting order, and is written only by its own
// iteration: the output is bit-identical for any thread count.
template <int Degree, int Axes>
MlsCounts MlsStrainSmoother::smooth_with(const ParticleStore& P, const CellSort& sort, const GridGeometry& grid,
                                         const std::array<const double*, 6>& in, const std::array<double*, 6>& out,
                                         const std::vector<std::uint8_t>& smooth_body) const {
  constexpr int T = mls_term_count(Degree, Axes);
  const int bc = sort.block_cells();
  const std::size_t cells_per_block = static_cast<std::size_t>(bc) * bc * bc;
  const std::vector<std::uint32_t>& cell_start = sort.cell_start();
  const std::int64_t blocks = static_cast<std::int64_t>(sort.block_count());
  const double inv_radius = 1.0 / radius_;
  const double rg = radius_ / grid.h;  // radius in cells
  std::size_t smoothed = 0, unsmoothed = 0;
#pragma omp parallel reduction(+ : smoothed, unsmoothed)
  {
    MlsScratch S;
#pragma omp for schedule(dynamic, 1)
    for (std::int64_t bi = 0; bi < blocks; ++bi) {
      const std::size_t base = static_cast<std::size_t>(bi) * cells_per_block;
      for (std::size_t l = 0; l < cells_per_block; ++l) {
        const std::uint32_t p_begin = cell_start[base + l], p_end = cell_start[base + l + 1];
        if (p_begin == p_end) continue;
        const ParticleBox box = box_and_copy_unsmoothed(P, grid, p_begin, p_end, smooth_body, in, out);
        if (box.empty()) continue;  // nothing to smooth in this cell
        std::size_t nc = gather_candidates(S, P, sort, box, rg);
        nc = keep_near_box(S, nc, box, radius_);
        bool one_body = true;
        for (std::size_t I = 1; I < nc; ++I) one_body = one_body && S.cbody[I] == S.cbody[0];
        for (std::uint32_t p = p_begin; p < p_end; ++p) {
          const std::uint16_t body = P.body[p];
          if (!smooth_body[body]) continue;  // copied above
          const double xp[3] = {P.x[0][p], P.x[1][p], P.x[2][p]};
          const std::size_t m = find_neighbours<Axes>(S, nc, xp, body, one_body, inv_radius, axis_list_);
          const std::size_t m_pad = (m + kLanes - 1) / kLanes * kLanes;
          double a[T];
          if (!fit_coefficients<Degree, Axes>(S, m, m_pad, settings_.min_rcond, a)) {
            for (int c = 0; c < 6; ++c) out[c][p] = in[c][p];  // the guard: unsmoothed
            ++unsmoothed;
            continue;
          }
          apply_fit<Degree, Axes>(S, m_pad, a, in, out, p);
          ++smoothed;
        }
      }
    }
  }
  return {smoothed, unsmoothed};
}

}  // namespace talus
