// Two ways to lay the MLS particle fit (Edo & Matsubara 2015, eq. 38-46; linear basis in 3D) on
// vector lanes, timed side by side on synthetic particles. It backs the measurements in
// docs/performance.md, "Why the particle fit stays above its target"; it is not talus code.
//
//   particles  - lanes over particles (what talus does, smoothing/mls_strain_smoother.cpp): a group
//                of 8 particles (one cell) in the lanes, its candidates (the particles near the
//                group's box) broadcast one by one, weight zero outside a lane's ball.
//   neighbours - lanes over neighbours, compacted (AVX-512 only): per particle, the candidates are
//                tested 8 at a time and the ones inside its ball compressed into a list
//                (vcompresspd), then the sums run over that list 8 at a time; the lanes' partial
//                sums are added at the end. No lane does wasted work, but every kept neighbour
//                costs a compress and a store per field.
//
// Both layouts compute the same fit (A = sum W F F^T, a = A^-1 e_0, d_eps_p = sum W a^T F d_eps_I
// for 6 components) and are checked against each other; they differ at round-off only (the
// neighbours layout sums in another order).
//
// Build and run (on the machine whose figures you want; -ffp-contract=fast measures fused
// multiply-adds):
//   g++ -O3 -march=native -fno-math-errno -ffp-contract=off tools/mls_lane_layouts.cpp -o /tmp/mls_lane_layouts
//   /tmp/mls_lane_layouts [radius in cells = 1] [jitter in cells = 0.08] [cells per axis = 40] [repeats = 3]
#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <random>
#include <vector>
#ifdef __AVX512F__
#include <immintrin.h>
#endif

// Lane vectors live only inside this file's inlined functions.
#pragma GCC diagnostic ignored "-Wpsabi"
#pragma GCC diagnostic ignored "-Wignored-attributes"  // std::vector of lane vectors

namespace {

// One register of doubles: 8 lanes with AVX-512, else 4 (talus's group widths; a cell of 8
// particles is then two groups over the same candidates).
#ifdef __AVX512F__
constexpr int kLanes = 8;
#else
constexpr int kLanes = 4;
#endif
typedef double Lanes __attribute__((vector_size(kLanes * sizeof(double)), may_alias));

[[gnu::always_inline]] inline Lanes sqrt_lanes(Lanes x) {
  Lanes r;
  for (int v = 0; v < kLanes; ++v) r[v] = __builtin_sqrt(x[v]);
  return r;
}
// Edo & Matsubara 2015, eq. 39, as talus evaluates it inside the ball (s < 1).
[[gnu::always_inline]] inline Lanes weight_inside(Lanes s) {
  const Lanes inner = 2.0 / 3.0 - 4.0 * s * s + 4.0 * s * s * s;
  const Lanes outer = 4.0 / 3.0 - 4.0 * s + 4.0 * s * s - 4.0 / 3.0 * s * s * s;
  return s < 0.5 ? inner : outer;
}

// a = A^-1 e_0 for the 4x4 symmetric A given by its upper triangle (10 entries): Cholesky.
void solve_fit(const double (&upper)[10], double (&a)[4]) {
  double A[4][4];
  for (int r = 0, e = 0; r < 4; ++r)
    for (int c = r; c < 4; ++c, ++e) A[r][c] = A[c][r] = upper[e];
  double L[4][4] = {};
  for (int j = 0; j < 4; ++j) {
    double d = A[j][j];
    for (int k = 0; k < j; ++k) d -= L[j][k] * L[j][k];
    L[j][j] = std::sqrt(d > 0.0 ? d : 1.0);
    for (int i = j + 1; i < 4; ++i) {
      double v = A[i][j];
      for (int k = 0; k < j; ++k) v -= L[i][k] * L[j][k];
      L[i][j] = v / L[j][j];
    }
  }
  double y[4];
  for (int i = 0; i < 4; ++i) {  // L y = e_0
    double v = i == 0 ? 1.0 : 0.0;
    for (int k = 0; k < i; ++k) v -= L[i][k] * y[k];
    y[i] = v / L[i][i];
  }
  for (int i = 3; i >= 0; --i) {  // L^T a = y
    double v = y[i];
    for (int k = i + 1; k < 4; ++k) v -= L[k][i] * a[k];
    a[i] = v / L[i][i];
  }
}

struct Particles {
  std::vector<double> x[3], inc[6];
  std::vector<int> cell_start;  // cells in (i, j, k) order, 8 particles each
};

using Clock = std::chrono::steady_clock;
double seconds_since(Clock::time_point t) { return std::chrono::duration<double>(Clock::now() - t).count(); }

struct Timing {
  double pass1 = 0.0, solve = 0.0, pass2 = 0.0;
};

// Lanes over particles: talus's layout (pass 1: A; solve; pass 2: the increments).
void fit_lanes_over_particles(const Particles& P, int cell, int first, const std::vector<int>& cand, double radius,
                              std::vector<Lanes> (&scratch)[4], std::vector<double>& out, Timing& t) {
  const int p0 = P.cell_start[cell] + first;
  const int nc = static_cast<int>(cand.size());
  for (auto& s : scratch)
    if (static_cast<int>(s.size()) < nc) s.resize(nc);
  const double inv = 1.0 / radius;
  const Lanes zero = {};
  Lanes xp[3];
  for (int v = 0; v < kLanes; ++v)
    for (int d = 0; d < 3; ++d) xp[d][v] = P.x[d][p0 + v];
  auto t0 = Clock::now();
  Lanes acc[10] = {};
  for (int I = 0; I < nc; ++I) {
    const int q = cand[I];
    const Lanes d0 = (P.x[0][q] - xp[0]) * inv, d1 = (P.x[1][q] - xp[1]) * inv, d2 = (P.x[2][q] - xp[2]) * inv;
    const Lanes r2 = d0 * d0 + d1 * d1 + d2 * d2;
    const auto in = r2 < 1.0;
    const Lanes w = in ? weight_inside(sqrt_lanes(in ? r2 : zero)) : zero;
    scratch[0][I] = d0, scratch[1][I] = d1, scratch[2][I] = d2, scratch[3][I] = w;
    const Lanes F[4] = {zero + 1.0, d0, d1, d2};
    Lanes WF[4];
    for (int r = 0; r < 4; ++r) WF[r] = w * F[r];
    for (int r = 0, e = 0; r < 4; ++r)
      for (int c = r; c < 4; ++c, ++e) acc[e] += WF[r] * F[c];
  }
  t.pass1 += seconds_since(t0);
  t0 = Clock::now();
  Lanes a[4];
  for (int v = 0; v < kLanes; ++v) {
    double upper[10], av[4];
    for (int e = 0; e < 10; ++e) upper[e] = acc[e][v];
    solve_fit(upper, av);
    for (int r = 0; r < 4; ++r) a[r][v] = av[r];
  }
  t.solve += seconds_since(t0);
  t0 = Clock::now();
  Lanes sum[6] = {};
  for (int I = 0; I < nc; ++I) {
    const int q = cand[I];
    const Lanes phi = (a[0] + a[1] * scratch[0][I] + a[2] * scratch[1][I] + a[3] * scratch[2][I]) * scratch[3][I];
    for (int c = 0; c < 6; ++c) sum[c] += phi * P.inc[c][q];
  }
  t.pass2 += seconds_since(t0);
  for (int v = 0; v < kLanes; ++v)
    for (int c = 0; c < 6; ++c) out[6 * (p0 + v) + c] = sum[c][v];
}

#ifdef __AVX512F__
[[gnu::always_inline]] inline double lane_total(Lanes v) { return ((v[0] + v[4]) + (v[2] + v[6])) + ((v[1] + v[5]) + (v[3] + v[7])); }

// Lanes over neighbours, compacted: per particle, the kept candidates' offsets, squared distance
// and six increments are compressed into lists, and the sums run along the lists.
struct Compacted {
  std::vector<double> column[9];  // the group's candidates: x, y, z, 6 increments (padded)
  std::vector<double> list[kLanes][10];  // per particle: d0, d1, d2, r2 (then the weight), 6 increments
  int count[kLanes] = {};
};

void fit_lanes_over_neighbours(const Particles& P, int cell, const std::vector<int>& cand, double radius,
                               Compacted& S, std::vector<double>& out, Timing& t) {
  const int p0 = P.cell_start[cell];
  const int nc = static_cast<int>(cand.size()), padded = (nc + kLanes - 1) / kLanes * kLanes;
  auto t0 = Clock::now();
  for (auto& c : S.column)
    if (static_cast<int>(c.size()) < padded) c.resize(padded);
  for (int I = 0; I < padded; ++I) {
    for (int d = 0; d < 3; ++d) S.column[d][I] = I < nc ? P.x[d][cand[I]] : HUGE_VAL;
    for (int c = 0; c < 6; ++c) S.column[3 + c][I] = I < nc ? P.inc[c][cand[I]] : 0.0;
  }
  const double inv = 1.0 / radius;
  const Lanes zero = {};
  double upper[kLanes][10];
  for (int v = 0; v < kLanes; ++v) {
    for (auto& l : S.list[v])
      if (static_cast<int>(l.size()) < padded + kLanes) l.resize(padded + kLanes);
    const __m512d xp0 = _mm512_set1_pd(P.x[0][p0 + v]), xp1 = _mm512_set1_pd(P.x[1][p0 + v]),
                  xp2 = _mm512_set1_pd(P.x[2][p0 + v]), vinv = _mm512_set1_pd(inv), one = _mm512_set1_pd(1.0);
    double* o[10];
    for (int k = 0; k < 10; ++k) o[k] = S.list[v][k].data();
    int n = 0;
    for (int I = 0; I < padded; I += kLanes) {
      const __m512d d0 = _mm512_mul_pd(_mm512_sub_pd(_mm512_loadu_pd(&S.column[0][I]), xp0), vinv);
      const __m512d d1 = _mm512_mul_pd(_mm512_sub_pd(_mm512_loadu_pd(&S.column[1][I]), xp1), vinv);
      const __m512d d2 = _mm512_mul_pd(_mm512_sub_pd(_mm512_loadu_pd(&S.column[2][I]), xp2), vinv);
      const __m512d r2 = _mm512_add_pd(_mm512_add_pd(_mm512_mul_pd(d0, d0), _mm512_mul_pd(d1, d1)), _mm512_mul_pd(d2, d2));
      const __mmask8 m = _mm512_cmp_pd_mask(r2, one, _CMP_LT_OQ);
      _mm512_storeu_pd(o[0] + n, _mm512_maskz_compress_pd(m, d0));
      _mm512_storeu_pd(o[1] + n, _mm512_maskz_compress_pd(m, d1));
      _mm512_storeu_pd(o[2] + n, _mm512_maskz_compress_pd(m, d2));
      _mm512_storeu_pd(o[3] + n, _mm512_maskz_compress_pd(m, r2));
      for (int c = 0; c < 6; ++c)
        _mm512_storeu_pd(o[4 + c] + n, _mm512_maskz_compress_pd(m, _mm512_loadu_pd(&S.column[3 + c][I])));
      n += __builtin_popcount(m);
    }
    const int pn = (n + kLanes - 1) / kLanes * kLanes;
    for (int J = n; J < pn; ++J) {  // padding: outside the ball, weight zero
      o[0][J] = o[1][J] = o[2][J] = 0.0;
      o[3][J] = 1.0;
      for (int c = 0; c < 6; ++c) o[4 + c][J] = 0.0;
    }
    S.count[v] = n;
    Lanes acc[10] = {};
    for (int J = 0; J < pn; J += kLanes) {
      Lanes d0, d1, d2, r2;
      std::memcpy(&d0, o[0] + J, sizeof(Lanes));
      std::memcpy(&d1, o[1] + J, sizeof(Lanes));
      std::memcpy(&d2, o[2] + J, sizeof(Lanes));
      std::memcpy(&r2, o[3] + J, sizeof(Lanes));
      const Lanes w = r2 < 1.0 ? weight_inside(sqrt_lanes(r2)) : zero;
      std::memcpy(o[3] + J, &w, sizeof(Lanes));
      const Lanes F[4] = {zero + 1.0, d0, d1, d2};
      Lanes WF[4];
      for (int r = 0; r < 4; ++r) WF[r] = w * F[r];
      for (int r = 0, e = 0; r < 4; ++r)
        for (int c = r; c < 4; ++c, ++e) acc[e] += WF[r] * F[c];
    }
    for (int e = 0; e < 10; ++e) upper[v][e] = lane_total(acc[e]);
  }
  t.pass1 += seconds_since(t0);
  t0 = Clock::now();
  double a[kLanes][4];
  for (int v = 0; v < kLanes; ++v) solve_fit(upper[v], a[v]);
  t.solve += seconds_since(t0);
  t0 = Clock::now();
  for (int v = 0; v < kLanes; ++v) {
    const double* o[10];
    for (int k = 0; k < 10; ++k) o[k] = S.list[v][k].data();
    const int pn = (S.count[v] + kLanes - 1) / kLanes * kLanes;
    Lanes sum[6] = {};
    for (int J = 0; J < pn; J += kLanes) {
      Lanes d0, d1, d2, w;
      std::memcpy(&d0, o[0] + J, sizeof(Lanes));
      std::memcpy(&d1, o[1] + J, sizeof(Lanes));
      std::memcpy(&d2, o[2] + J, sizeof(Lanes));
      std::memcpy(&w, o[3] + J, sizeof(Lanes));
      const Lanes phi = (a[v][0] + a[v][1] * d0 + a[v][2] * d1 + a[v][3] * d2) * w;
      for (int c = 0; c < 6; ++c) {
        Lanes e;
        std::memcpy(&e, o[4 + c] + J, sizeof(Lanes));
        sum[c] += phi * e;
      }
    }
    for (int c = 0; c < 6; ++c) out[6 * (p0 + v) + c] = lane_total(sum[c]);
  }
  t.pass2 += seconds_since(t0);
}
#endif

}  // namespace

int main(int argc, char** argv) {
  const double radius = argc > 1 ? std::atof(argv[1]) : 1.0;   // cells (the cell size is 1)
  const double jitter = argc > 2 ? std::atof(argv[2]) : 0.08;  // cells, about a 2x2x2 lattice per cell
  const int n_cells = argc > 3 ? std::atoi(argv[3]) : 40;      // per axis
  const int repeats = argc > 4 ? std::atoi(argv[4]) : 3;
  if (!(radius > 0.0) || !(jitter >= 0.0 && jitter < 0.25) || n_cells < 3 || repeats < 1) {
    std::fprintf(stderr, "usage: %s [radius > 0] [0 <= jitter < 0.25] [cells per axis >= 3] [repeats >= 1]\n", argv[0]);
    return 2;
  }
  Particles P;
  std::mt19937 rng(1);
  std::uniform_real_distribution<double> U(-1.0, 1.0);
  for (int i = 0; i < n_cells; ++i)
    for (int j = 0; j < n_cells; ++j)
      for (int k = 0; k < n_cells; ++k) {
        P.cell_start.push_back(static_cast<int>(P.x[0].size()));
        const int c[3] = {i, j, k};
        for (int s = 0; s < 8; ++s) {
          for (int d = 0; d < 3; ++d) P.x[d].push_back(c[d] + 0.25 + 0.5 * ((s >> d) & 1) + jitter * U(rng));
          for (int e = 0; e < 6; ++e) P.inc[e].push_back(U(rng));
        }
      }
  P.cell_start.push_back(static_cast<int>(P.x[0].size()));
  const std::size_t np = P.x[0].size();
  // Candidates per cell: the particles of the cells within reach whose distance to the group's
  // box is below the radius, in cell order (as talus gathers them).
  const int reach = static_cast<int>(std::ceil(radius + 2.0 * jitter));
  std::vector<std::vector<int>> cand(P.cell_start.size() - 1);
  double candidates = 0.0, inside = 0.0;
  for (int i = 0; i < n_cells; ++i)
    for (int j = 0; j < n_cells; ++j)
      for (int k = 0; k < n_cells; ++k) {
        const int cell = (i * n_cells + j) * n_cells + k;
        double lo[3] = {HUGE_VAL, HUGE_VAL, HUGE_VAL}, hi[3] = {-HUGE_VAL, -HUGE_VAL, -HUGE_VAL};
        for (int p = P.cell_start[cell]; p < P.cell_start[cell + 1]; ++p)
          for (int d = 0; d < 3; ++d) lo[d] = std::min(lo[d], P.x[d][p]), hi[d] = std::max(hi[d], P.x[d][p]);
        for (int a = std::max(0, i - reach); a <= std::min(n_cells - 1, i + reach); ++a)
          for (int b = std::max(0, j - reach); b <= std::min(n_cells - 1, j + reach); ++b)
            for (int c = std::max(0, k - reach); c <= std::min(n_cells - 1, k + reach); ++c) {
              const int h = (a * n_cells + b) * n_cells + c;
              for (int q = P.cell_start[h]; q < P.cell_start[h + 1]; ++q) {
                double g2 = 0.0;
                for (int d = 0; d < 3; ++d) {
                  const double gap = std::max(lo[d] - P.x[d][q], P.x[d][q] - hi[d]);
                  g2 += gap > 0.0 ? gap * gap : 0.0;
                }
                if (g2 < radius * radius) cand[cell].push_back(q);
              }
            }
        candidates += cand[cell].size();
        for (int p = P.cell_start[cell]; p < P.cell_start[cell + 1]; ++p)
          for (int q : cand[cell]) {
            double r2 = 0.0;
            for (int d = 0; d < 3; ++d) r2 += (P.x[d][q] - P.x[d][p]) * (P.x[d][q] - P.x[d][p]);
            inside += r2 < radius * radius ? 1.0 : 0.0;
          }
      }
  const double groups = static_cast<double>(cand.size());
  std::printf("%zu particles, radius %g cells, jitter %g, %d lanes: %.1f candidates per cell of 8, %.1f neighbours "
              "per particle (%.0f%% of the lane evaluations of the particles layout do work)\n",
              np, radius, jitter, kLanes, candidates / groups, inside / static_cast<double>(np),
              100.0 * inside / (candidates * 8));
  std::vector<double> out_particles(6 * np), out_neighbours(6 * np);
  std::vector<Lanes> scratch[4];
  for (int rep = 0; rep < repeats; ++rep) {
    Timing tp;
    for (std::size_t c = 0; c < cand.size(); ++c)
      for (int first = 0; first < 8; first += kLanes)
        fit_lanes_over_particles(P, static_cast<int>(c), first, cand[c], radius, scratch, out_particles, tp);
    const double ns = 1e9 / static_cast<double>(np);
    std::printf("particles:  pass 1 %6.1f  solve %5.1f  pass 2 %5.1f  total %6.1f ns/particle\n", tp.pass1 * ns,
                tp.solve * ns, tp.pass2 * ns, (tp.pass1 + tp.solve + tp.pass2) * ns);
#ifdef __AVX512F__
    Timing tn;
    Compacted S;
    for (std::size_t c = 0; c < cand.size(); ++c)
      fit_lanes_over_neighbours(P, static_cast<int>(c), cand[c], radius, S, out_neighbours, tn);
    double worst = 0.0, scale = 0.0;
    for (std::size_t i = 0; i < out_particles.size(); ++i) {
      worst = std::max(worst, std::abs(out_particles[i] - out_neighbours[i]));
      scale = std::max(scale, std::abs(out_particles[i]));
    }
    std::printf("neighbours: pass 1 %6.1f  solve %5.1f  pass 2 %5.1f  total %6.1f ns/particle (x%.2f the particles "
                "layout's total; largest difference %.1e of the largest result)\n",
                tn.pass1 * ns, tn.solve * ns, tn.pass2 * ns, (tn.pass1 + tn.solve + tn.pass2) * ns,
                (tp.pass1 + tp.solve + tp.pass2) / (tn.pass1 + tn.solve + tn.pass2), worst / scale);
#else
    if (rep == 0) std::printf("neighbours: needs AVX-512 (build with -march=native on such a CPU)\n");
#endif
  }
  return 0;
}
