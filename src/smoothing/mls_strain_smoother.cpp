#include "talus/smoothing/mls_strain_smoother.hpp"

#include "talus/core/error.hpp"

#include <Eigen/Cholesky>
#include <Eigen/Core>
#include <fmt/core.h>

#include <algorithm>
#include <cmath>

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

constexpr int kBatch = 128;  // neighbours buffered before their sums are added to A and M

/// Distance (in cells) from grid coordinate x to the cell [i, i + 1).
inline double gap_to_cell(int i, double x) { return std::max({0.0, i - x, x - (i + 1)}); }

}  // namespace

template <int Degree, int Axes>
MlsCounts MlsStrainSmoother::smooth_with(const ParticleStore& P, const CellSort& sort, const GridGeometry& grid,
                                         const std::array<const double*, 6>& in, const std::array<double*, 6>& out,
                                         const std::vector<std::uint8_t>& smooth_body) const {
  constexpr int T = mls_term_count(Degree, Axes);
  using MatT = Eigen::Matrix<double, T, T>;
  using VecT = Eigen::Matrix<double, T, 1>;
  const std::int64_t n = static_cast<std::int64_t>(P.size());
  const int bc = sort.block_cells();
  const std::size_t cells_per_block = static_cast<std::size_t>(bc) * bc * bc;
  const std::vector<std::uint32_t>& cell_start = sort.cell_start();
  const double inv_radius = 1.0 / radius_;
  const double rg = radius_ / grid.h;  // radius in cells
  const double rg2 = rg * rg;
  const int reach = static_cast<int>(std::ceil(rg));
  const std::array<int, 3> axes = axis_list_;
  const double min_rcond = settings_.min_rcond;
  std::size_t smoothed = 0, unsmoothed = 0;

#pragma omp parallel for schedule(dynamic, 256) reduction(+ : smoothed, unsmoothed)
  for (std::int64_t pi = 0; pi < n; ++pi) {
    const std::size_t p = static_cast<std::size_t>(pi);
    const std::uint16_t body = P.body[p];
    if (!smooth_body[body]) {
      for (int c = 0; c < 6; ++c) out[c][p] = in[c][p];
      continue;
    }
    const double xp[3] = {P.x[0][p], P.x[1][p], P.x[2][p]};
    double xg[3];
    int cell[3];
    for (int d = 0; d < 3; ++d) {
      xg[d] = grid.to_grid(d, xp[d]);
      cell[d] = static_cast<int>(std::floor(xg[d]));
    }
    MatT A = MatT::Zero();                         // seed 000 eq. 42 (upper triangle accumulated)
    Eigen::Matrix<double, T, 6> M = Eigen::Matrix<double, T, 6>::Zero();  // sum_I W_I F_I d_eps_I^T = B d_eps
    int count = 0;
    // Neighbours are buffered (weight, basis, increments) and added to A and M in batches: the
    // sums over a batch are simple dot products the compiler vectorises.
    alignas(64) double Fb[T][kBatch], WFb[T][kBatch], Eb[6][kBatch];
    int nb = 0;
    auto flush = [&]() {
      for (int r = 0; r < T; ++r) {
        for (int c = r; c < T; ++c) {
          double sum = 0.0;
#pragma omp simd reduction(+ : sum)
          for (int I = 0; I < nb; ++I) sum += WFb[r][I] * Fb[c][I];
          A(r, c) += sum;
        }
        for (int c = 0; c < 6; ++c) {
          double sum = 0.0;
#pragma omp simd reduction(+ : sum)
          for (int I = 0; I < nb; ++I) sum += WFb[r][I] * Eb[c][I];
          M(r, c) += sum;
        }
      }
      count += nb;
      nb = 0;
    };
    // The cells that meet the ball of radius h around x_p; along k, the cells of one block are
    // contiguous in the store, so each (i, j) column is one particle range per block.
    for (int i = std::max(0, cell[0] - reach); i <= cell[0] + reach; ++i) {
      const double gi = gap_to_cell(i, xg[0]);
      if (gi * gi >= rg2) continue;
      for (int j = std::max(0, cell[1] - reach); j <= cell[1] + reach; ++j) {
        const double gj = gap_to_cell(j, xg[1]);
        const double rem = rg2 - gi * gi - gj * gj;
        if (rem <= 0.0) continue;
        const double half = std::sqrt(rem);
        int k = std::max(0, static_cast<int>(std::floor(xg[2] - half)));
        const int k_last = static_cast<int>(std::floor(xg[2] + half));
        while (k <= k_last) {
          const int k_end = std::min(k_last, (k / bc) * bc + bc - 1);  // last cell of this block along k
          const long long b = sort.active_block_of_cell(i, j, k);
          if (b >= 0) {
            // Local cell within the block: the block's origin is the cell index rounded down to a
            // multiple of bc (cheaper than CellSort::block_origin's divisions by the block counts).
            const std::size_t base = static_cast<std::size_t>(b) * cells_per_block;
            const std::size_t l0 = static_cast<std::size_t>(((i % bc) * bc + (j % bc)) * bc + (k % bc));
            const std::size_t l1 = l0 + static_cast<std::size_t>(k_end - k);
            for (std::uint32_t q = cell_start[base + l0]; q < cell_start[base + l1 + 1]; ++q) {
              if (P.body[q] != body) continue;  // strain is discontinuous across bodies
              const double dx[3] = {(P.x[0][q] - xp[0]) * inv_radius, (P.x[1][q] - xp[1]) * inv_radius,
                                    (P.x[2][q] - xp[2]) * inv_radius};
              const double s2 = dx[0] * dx[0] + dx[1] * dx[1] + dx[2] * dx[2];
              if (s2 >= 1.0) continue;
              const double w = mls_weight(std::sqrt(s2));  // seed 000 eq. 39
              double u[Axes], F[T];
              for (int a = 0; a < Axes; ++a) u[a] = dx[axes[a]];
              mls_basis<Degree, Axes>(u, F);
              for (int r = 0; r < T; ++r) {
                Fb[r][nb] = F[r];
                WFb[r][nb] = w * F[r];
              }
              for (int c = 0; c < 6; ++c) Eb[c][nb] = in[c][q];
              if (++nb == kBatch) flush();
            }
          }
          k = k_end + 1;
        }
      }
    }
    flush();
    bool ok = count >= T;
    VecT a;
    if (ok) {
      A.template triangularView<Eigen::StrictlyLower>() = A.transpose();
      const Eigen::LLT<MatT> llt(A);
      ok = llt.info() == Eigen::Success && llt.rcond() >= min_rcond;
      if (ok) a = llt.solve(VecT::Unit(0));  // a = A^-1 F(u_p), F(0) = e_0 (eq. 45)
      ok = ok && a.allFinite();
    }
    if (!ok) {  // guard: too few neighbours for the basis, or A (nearly) singular
      for (int c = 0; c < 6; ++c) out[c][p] = in[c][p];
      ++unsmoothed;
      continue;
    }
    for (int c = 0; c < 6; ++c) out[c][p] = a.dot(M.col(c));  // eq. 46: sum_I Phi_I d_eps_I
    ++smoothed;
  }
  return {smoothed, unsmoothed};
}

}  // namespace talus
