// The particle-grid transfer kernels: templates over the shape function and the terrain type,
// compiled once per instruction set. Each shape's file (transfers_<shape>.cpp, through
// shape_kernels_per_target.h) includes this once per Highway target, so the four shapes compile in parallel.
// The code is plain C++: compiled for AVX2 or AVX-512 the compiler puts the per-particle tables and
// the factorised sums in wider registers. It keeps every operation and its order (no fused
// multiply-add, -ffp-contract=off; no reassociation), so every path gives the same bits;
// tests/solver/isa_paths_test.cpp checks it.

// Highway's per-target include guard: foreach_target includes this once for each target.
#if defined(TALUS_TRANSFER_KERNELS_INL_H_) == defined(HWY_TARGET_TOGGLE)
#ifdef TALUS_TRANSFER_KERNELS_INL_H_
#undef TALUS_TRANSFER_KERNELS_INL_H_
#else
#define TALUS_TRANSFER_KERNELS_INL_H_
#endif

#include <hwy/highway.h>

#include "talus/grid/terrain.hpp"
#include "talus/transfer/stencil.hpp"
#include "talus/transfer/transfers.hpp"

#include <omp.h>

#include <algorithm>
#include <array>
#include <climits>
#include <cmath>
#include <cstdint>
#include <limits>
#include <span>
#include <stdexcept>
#include <type_traits>

HWY_BEFORE_NAMESPACE();
namespace talus {
namespace HWY_NAMESPACE {

namespace {

/// The particle domain's half widths in grid units, as the shape function wants them: none for a
/// material point, l_p0 = V0^(1/3)/2 for uGIMP (Edo & Matsubara 2015, eq. 59), the current per-axis half widths
/// for cpGIMP (eq. 57-58). The shape clamps them to what its support holds.
/// uGIMP's cube root is a libm call (12% of a uGIMP step, three times per particle and step), and a
/// body's particles usually share one V0: the last V0 and its half width are kept, and a particle with
/// the same V0 reuses them (the same bits as computing them again).
template <class Shape>
class HalfWidths {
 public:
  explicit HalfWidths(double inv_h) : inv_h_(inv_h) {}
  [[gnu::always_inline]] inline void operator()(const ParticleStore& P, std::size_t p, double hw[3]) {
    if constexpr (Shape::kDomain == DomainSource::Initial) {
      const double v0 = P.volume0[p];
      if (v0 != last_v0_) {  // a NaN never equals itself: computed every time
        last_v0_ = v0;
        last_ = 0.5 * std::cbrt(v0) * inv_h_;
      }
      hw[0] = hw[1] = hw[2] = last_;
    } else if constexpr (Shape::kDomain == DomainSource::Current) {
      for (int d = 0; d < 3; ++d) hw[d] = P.domain[d][p] * inv_h_;
    } else {
      hw[0] = hw[1] = hw[2] = 0.0;
    }
  }

 private:
  double inv_h_;
  double last_v0_ = std::numeric_limits<double>::quiet_NaN(), last_ = 0.0;
};

}  // namespace

namespace {

namespace hn = hwy::HWY_NAMESPACE;

/// One particle's scatter into node records with vector registers. A record's 8 doubles are two
/// halves: mass and momentum (slots 0-3), force and an unused slot (4-7), each one vector of 4 lanes
/// (two on narrower targets). Every node gets
///   low half  += A wz[c],                 A = (m, m v) wxy,
///   high half += F wz[c] + G gz[c],       F = (-V sigma) . (gxy, wgy, 0),  G = (-V sigma) . (0, 0, wxy) (- slope term),
/// per (a, b) row. Vectors of 4 even where the CPU has 8 lanes: one 8-lane vector per record did
/// the force's terms on the mass and momentum lanes too (multiplied by exact zeros), and Zen 4 runs
/// a 512-bit operation as two 256-bit halves. Only the halves that hold scattered fields are loaded
/// and stored (the remap's momentum: the low half; USF's force: the high half).
/// Bits: each field's operations are the scalar scatter's (Mul and Add, no FMA), plus, on the
/// lanes of a half that hold no field of this particle's sum, additions of exact zeros. Those can
/// only turn a -0 into +0, and a node sum that starts at +0 never holds -0, so every node ends with
/// the same bits (tests/solver/isa_paths_test.cpp and the bit-identity tests check it). Slots of
/// fields not scattered keep their values (a blend).
template <bool with_mass, bool with_momentum, bool with_force>
class RecordScatter {
  using D = hn::CappedTag<double, 4>;
  using V = hn::Vec<D>;
  static constexpr int kLanes = static_cast<int>(hn::MaxLanes(D()));
  static constexpr int kParts = 4 / kLanes;  // vectors per half record
  static_assert(4 % kLanes == 0 && kMassSlot == 0 && kMomentumSlot == 1 && kForceSlot == 4,
                "the halves: mass and momentum in slots 0-3, the force in slots 4-6");
  static constexpr bool kLow = with_mass || with_momentum, kHigh = with_force;
  static constexpr bool kBlendLow = !(with_mass && with_momentum);

 public:
  RecordScatter() {
    alignas(64) double written[4] = {};  // the low half's; the high half's unused slot 7 gets exact zeros
    if (with_mass) written[kMassSlot] = 1.0;
    for (int d = 0; d < 3; ++d)
      if (with_momentum) written[kMomentumSlot + d] = 1.0;
    for (int i = 0; i < kParts; ++i) {
      keep_low_[i] = hn::Ne(hn::Load(D(), written + i * kLanes), hn::Zero(D()));
      for (int half = 0; half < 2; ++half) {
        const V lane = hn::Iota(D(), static_cast<double>(4 * half + i * kLanes));
        for (int slot = 0; slot < 4; ++slot) is_slot_[half][slot][i] = hn::Eq(lane, hn::Set(D(), 4 * half + slot));
      }
    }
  }

  /// The particle's mass, momentum and -V sigma (Voigt: xx, yy, zz, yz, xz, xy).
  /// The vectors are put together in registers, a broadcast blended into each lane. Written
  /// into a table on the stack and loaded as vectors, they cost a failed store-to-load forward per
  /// vector (several narrow stores read by one wide load): 41% of cpGIMP's scatter sat there.
  void set_particle(double m, const double mv[3], const double s[6]) {
    const double rows[3][3] = {{s[0], s[5], s[4]}, {s[5], s[1], s[3]}, {s[4], s[3], s[2]}};  // sigma_dj
    for (int i = 0; i < kParts; ++i) {
      if constexpr (kLow) {
        V p0 = hn::IfThenElseZero(is_slot_[0][kMassSlot][i], hn::Set(D(), m));
        for (int d = 0; d < 3; ++d) p0 = hn::IfThenElse(is_slot_[0][kMomentumSlot + d][i], hn::Set(D(), mv[d]), p0);
        p0_[i] = p0;
      }
      if constexpr (kHigh) {
        V sj[3];
        for (int j = 0; j < 3; ++j) {
          sj[j] = hn::IfThenElseZero(is_slot_[1][0][i], hn::Set(D(), rows[0][j]));
          for (int d = 1; d < 3; ++d) sj[j] = hn::IfThenElse(is_slot_[1][d][i], hn::Set(D(), rows[d][j]), sj[j]);
        }
        s1_[i] = sj[0];
        s2_[i] = sj[1];
        s3_[i] = sj[2];
      }
    }
  }

  /// The (a, b) row's factors: wxy = wx wy, gxy = gx wy, wgy = wx gy, and for a terrain grid
  /// t = z_b' wxy (dN/dx_phys = dN/dx - z_b' dN/dw).
  template <bool kTerrain>
  void set_row(double wxy, double gxy, double wgy, double t) {
    const V w = hn::Set(D(), wxy);
    for (int i = 0; i < kParts; ++i) {
      if constexpr (kLow) a_[i] = hn::Mul(p0_[i], w);
      if constexpr (kHigh) {
        f_[i] = hn::Add(hn::Mul(s1_[i], hn::Set(D(), gxy)), hn::Mul(s2_[i], hn::Set(D(), wgy)));
        g_[i] = hn::Mul(s3_[i], w);
        if constexpr (kTerrain) g_[i] = hn::Sub(g_[i], hn::Mul(s1_[i], hn::Set(D(), t)));
      }
    }
  }

  /// record += (A wz | F wz + G gz), each half only when it holds scattered fields.
  void add_to(double* record, double wz, double gz) const {
    const V vw = hn::Set(D(), wz);
    for (int i = 0; i < kParts; ++i) {
      if constexpr (kLow) {
        double* const part = record + i * kLanes;
        const V old = hn::Load(D(), part);
        const V sum = hn::Add(old, hn::Mul(a_[i], vw));
        hn::Store(kBlendLow ? hn::IfThenElse(keep_low_[i], sum, old) : sum, D(), part);
      }
      if constexpr (kHigh) {
        double* const part = record + 4 + i * kLanes;
        const V old = hn::Load(D(), part);
        const V sum = hn::Add(old, hn::Add(hn::Mul(f_[i], vw), hn::Mul(g_[i], hn::Set(D(), gz))));
        hn::Store(sum, D(), part);
      }
    }
  }

 private:
  V p0_[kParts], s1_[kParts], s2_[kParts], s3_[kParts], a_[kParts], f_[kParts], g_[kParts];
  hn::Mask<D> keep_low_[kParts];
  hn::Mask<D> is_slot_[2][4][kParts];  // lane == slot, per half and part of the record
};

/// The vectors of a node record (`kStride` doubles) that hold the 3 doubles at `kSlot`: the
/// gathers load only those (RecordGather, RecordVelocityGradient). When the three lie in one aligned
/// group of 4 doubles (half a record, half a cache line), the vectors are at most 4 wide even where
/// the CPU has 8 lanes: the other lanes were never used, and Zen 4 runs a 512-bit operation as two
/// 256-bit halves.
template <int kStride, int kSlot>
struct RecordSlots {
  static constexpr int kWidth = (kStride > 4 && kSlot / 4 == (kSlot + 2) / 4) ? 4 : kStride;
  using D = hn::CappedTag<double, kWidth>;
  using V = hn::Vec<D>;
  static constexpr int kLanes = static_cast<int>(hn::MaxLanes(D()));
  static constexpr int kFirst = kSlot / kLanes, kLast = (kSlot + 2) / kLanes;
  static constexpr int kParts = kLast - kFirst + 1;
  /// Where component d lands when the kParts vectors are stored one after another.
  static constexpr int lane_of(int d) { return kSlot + d - kFirst * kLanes; }

  explicit RecordSlots(const double* records) : records(records) {}
  /// Vector `part` (0 .. kParts-1) of node n's record.
  V load(std::size_t n, int part) const { return hn::Load(D(), records + n * kStride + (kFirst + part) * kLanes); }

  const double* records;
};

/// One node vector (3 doubles at `kSlot` of records of `kStride` doubles: v^L - v in the node
/// records' force slots after the grid update, or v^L in its own records) interpolated to a particle
/// with vector registers: each (a, b) row sums wz[c] record over its nodes, the particle wxy row.
/// Only the vectors that hold the three slots are loaded; every lane does the scalar gather's
/// operations in its order, so those lanes get the same bits (the others are unused).
template <int kStride, int kSlot>
class RecordGather {
  using Slots = RecordSlots<kStride, kSlot>;
  using D = typename Slots::D;
  using V = typename Slots::V;
  static constexpr int kParts = Slots::kParts, kLanes = Slots::kLanes;

 public:
  explicit RecordGather(const double* records) : slots_(records) {}
  void start_particle() {
    for (int i = 0; i < kParts; ++i) particle_[i] = hn::Zero(D());
  }
  void start_row() {
    for (int i = 0; i < kParts; ++i) row_[i] = hn::Zero(D());
  }
  void add_node(std::size_t n, double wz) {
    const V w = hn::Set(D(), wz);
    for (int i = 0; i < kParts; ++i) row_[i] = hn::Add(row_[i], hn::Mul(w, slots_.load(n, i)));
  }
  void end_row(double wxy) {
    const V w = hn::Set(D(), wxy);
    for (int i = 0; i < kParts; ++i) particle_[i] = hn::Add(particle_[i], hn::Mul(w, row_[i]));
  }
  /// sum_i N_i u_i
  void value(double out[3]) const {
    alignas(64) double lanes[kParts * kLanes];
    for (int i = 0; i < kParts; ++i) hn::Store(particle_[i], D(), lanes + i * kLanes);
    for (int d = 0; d < 3; ++d) out[d] = lanes[Slots::lane_of(d)];
  }

 private:
  Slots slots_;
  V row_[kParts], particle_[kParts];
};

/// A block's box (BlockBuffers) as a scatter's target: `edge`^3 node records whose first node is
/// `first`, and the range [lo, hi) of box-local nodes (per axis) that the scatter has reached.
struct BoxTarget {
  std::array<int, 3> first{};
  int edge = 0;
  std::array<int, 3> lo{INT_MAX, INT_MAX, INT_MAX}, hi{INT_MIN, INT_MIN, INT_MIN};
};

/// Calls `write(ix, iy, iz)` with the node indices of a stencil's rows and columns where a scatter
/// writes: the grid's (the stencil's own tables) or, with a box, the box's, after widening the box's
/// reached range to them. (In the P2G the box is a run-time choice, not a template parameter, to keep
/// the number of compiled scatter functions, and the build time, down; `write` is forced inline in
/// both branches so each copy of the innermost loops indexes tables the compiler can see: one shared
/// copy through a pointer chosen at run time ran the B-spline's P2G 9% slower on the AVX2 VM. The
/// MUSL remap inside the G2P keeps the box a template parameter, gather_blocks' `into_boxes`: the
/// run-time choice there cost cpGIMP's G2P 7%.)
template <class S, class Write>
[[gnu::always_inline]] inline void with_scatter_index(const S& s, BoxTarget* box, Write&& write) {
  constexpr int N = S::N;
  if (!box) {
    write(s.ix, s.iy, s.iz);
    return;
  }
  for (int d = 0; d < 3; ++d) {
    const int f = s.first[d] - box->first[d];
    box->lo[d] = std::min(box->lo[d], f);
    box->hi[d] = std::max(box->hi[d], f + N);
  }
  const std::size_t edge = static_cast<std::size_t>(box->edge);
  std::size_t x[N], y[N], z[N];
  for (int a = 0; a < N; ++a) {
    x[a] = static_cast<std::size_t>(s.first[0] + a - box->first[0]) * edge * edge;
    y[a] = static_cast<std::size_t>(s.first[1] + a - box->first[1]) * edge;
    z[a] = static_cast<std::size_t>(s.first[2] + a - box->first[2]);
  }
  write(x, y, z);
}

// The fields to scatter are template parameters, so each combination compiles to a loop without
// the tests (the innermost loop runs 8-64 times per particle). One block's particles into
// `records`: the grid's, or with `box` the block's box (BlockBuffers).
template <class Shape, class Terrain, bool with_mass, bool with_momentum, bool with_force>
void scatter_block(const ParticleStore& P, const CellSort& sort, const Grid& grid, std::size_t b, double* records,
                   BoxTarget* box) {
  const Terrain& terrain = grid.template terrain<Terrain>();
  const double inv_h = 1.0 / grid.geometry().h;
  ParticleStencil<Shape> stencil;
  HalfWidths<Shape> half_widths(inv_h);
  RecordScatter<with_mass, with_momentum, with_force> scatter;
  for (std::size_t p = sort.block_begin(b); p < sort.block_end(b); ++p) {
    double hw[3];
    half_widths(P, p, hw);
    const double m = P.mass[p];
    const double mv[3] = {m * P.v[0][p], m * P.v[1][p], m * P.v[2][p]};
    // -V sigma, for f_int = -sum V_p sigma_p grad N (Edo & Matsubara 2015, eq. 22)
    const double vol = P.volume[p];
    double minus_v_sigma[6];
    for (int c = 0; c < 6; ++c) minus_v_sigma[c] = -vol * P.stress[c][p];
    scatter.set_particle(m, mv, minus_v_sigma);
    stencil.visit(grid, terrain, P.x[0][p], P.x[1][p], P.x[2][p], hw, [&](const auto& s) {
      constexpr int N = std::decay_t<decltype(s)>::N;
      // Sum factorisation: with grad N = (gx wy wz, wx gy wz, wx wy gz) (Stencil::gradient) the
      // force on node (a, b, c) is wz[c] A + gz[c] B with A, B fixed per (a, b) row, so the
      // innermost loop does 2 multiply-adds per component instead of forming the gradient.
      const auto scatter_rows = [&](const std::size_t* ix, const std::size_t* iy,
                                    const std::size_t* iz) __attribute__((always_inline)) {
        for (int a = 0; a < N; ++a)
          for (int bb = 0; bb < N; ++bb) {
            const std::size_t row = ix[a] + iy[bb];
            const double wxy = s.wx[a] * s.wy[bb];
            scatter.template set_row<!Terrain::kIsFlat>(wxy, s.gx[a] * s.wy[bb], s.wx[a] * s.gy[bb],
                                                        s.terrain_slope * wxy);
            for (int c = 0; c < N; ++c) scatter.add_to(records + (row + iz[c]) * kNodeRecord, s.wz[c], s.gz[c]);
          }
      };
      with_scatter_index(s, box, scatter_rows);
    });
  }
}

template <class Shape, class Terrain, bool with_mass, bool with_momentum, bool with_force>
void scatter_fields(const ParticleStore& P, const CellSort& sort, Grid& grid, BlockBuffers* buffers,
                    ColourPassTiming* timing) {
  double* const records = grid.records();
  double pass_start = timing ? omp_get_wtime() : 0.0;
  if (buffers) {
    // Without colour passes: every block into its own box, all blocks in one pass (any order);
    // BlockBuffers::add_sum_stage adds the boxes afterwards. A timing record lists it as colour 0.
    const std::vector<std::uint32_t>& order = sort.blocks_in_work_order();
    const std::size_t count = order.size();
    if (timing) timing->block_seconds[0].assign(count, 0.0);
#pragma omp parallel for schedule(dynamic, 1)
    for (std::size_t bi = 0; bi < count; ++bi) {
      const std::size_t b = order[bi];
      const double block_start = timing ? omp_get_wtime() : 0.0;
      BoxTarget box{buffers->first_node(b), buffers->edge()};
      scatter_block<Shape, Terrain, with_mass, with_momentum, with_force>(P, sort, grid, b, buffers->open_box(b), &box);
      buffers->close_box(b, box.lo, box.hi);
      if (timing) timing->block_seconds[0][bi] = omp_get_wtime() - block_start;
    }
    if (timing) timing->wall[0] = omp_get_wtime() - pass_start;
    return;
  }
  if (timing)
    for (int colour = 0; colour < 8; ++colour) timing->block_seconds[colour].assign(sort.colour(colour).size(), 0.0);
  // One parallel region for the 8 colours: a colour's blocks may share nodes with the next colour's,
  // so each colour ends at the implicit barrier of its loop; a barrier costs less than a fork/join.
#pragma omp parallel
  for (int colour = 0; colour < 8; ++colour) {
    const auto& blocks = sort.colour(colour);
    const std::size_t count = blocks.size();
#pragma omp for schedule(dynamic, 1)
    for (std::size_t bi = 0; bi < count; ++bi) {
      const std::size_t b = blocks[bi];
      const double block_start = timing ? omp_get_wtime() : 0.0;
      scatter_block<Shape, Terrain, with_mass, with_momentum, with_force>(P, sort, grid, b, records, nullptr);
      if (timing) timing->block_seconds[colour][bi] = omp_get_wtime() - block_start;
    }
    if (timing) {
#pragma omp master
      {
        const double now = omp_get_wtime();
        timing->wall[colour] = now - pass_start;
        pass_start = now;
      }
    }
  }
}

}  // namespace

template <class Shape, class Terrain>
void scatter_impl(const ParticleStore& P, const CellSort& sort, Grid& grid, ScatterFields fields, BlockBuffers* buffers,
                  ColourPassTiming* timing) {
  switch (fields) {
    case ScatterFields::MassMomentumForce: scatter_fields<Shape, Terrain, true, true, true>(P, sort, grid, buffers, timing); break;
    case ScatterFields::Momentum: scatter_fields<Shape, Terrain, false, true, false>(P, sort, grid, buffers, timing); break;
    case ScatterFields::MassMomentum: scatter_fields<Shape, Terrain, true, true, false>(P, sort, grid, buffers, timing); break;
    case ScatterFields::Force: scatter_fields<Shape, Terrain, false, false, true>(P, sort, grid, buffers, timing); break;
  }
}

namespace {

// G2P over the blocks `blocks` (all blocks, or one colour's), in parallel. With `remap` each
// particle's new momentum m_p v_p is scattered into grid.momentum with the same stencil right
// after its gather (the MUSL remap, Edo & Matsubara 2015, eq. 52): that is race-free only when the blocks are
// one colour's, and it saves the remap's own pass over the particles and its weight evaluation.
// Called by every thread of a parallel region (an orphaned `omp for`); each thread's flags are its own
// (merged by gather_impl: OR and max, the same for any thread count).
// With `into_boxes` the remap scatters into each block's own box in `buffers` (BlockBuffers) instead, and the blocks
// may be any blocks at once.
template <class Shape, class Terrain, bool remap, bool into_boxes>
void gather_blocks(ParticleStore& P, const CellSort& sort, Grid& grid, const std::array<std::span<double>, 3>& displacement,
                   std::vector<double>& block_damping, const GatherOptions& options,
                   const std::vector<std::uint32_t>& blocks, GatherResult& flags, std::vector<double>* block_seconds,
                   BlockBuffers* buffers) {
  const double dt = options.dt, pic_fraction = options.pic_fraction;
  std::vector<double>* const increment_kinetic = options.block_increment_kinetic;
  const double max_d2 = options.max_displacement * options.max_displacement;
  const Terrain& terrain = grid.template terrain<Terrain>();
  const GridGeometry& g = grid.geometry();
  const auto nodes = g.nodes();
  // v^L - v is the force slots of the node records (grid.velocity_change()), v^L its own arrays
  double* const records = grid.records();

  double* disp[3] = {displacement[0].data(), displacement[1].data(), displacement[2].data()};
  bool needs_sort = flags.needs_sort, large = flags.large_displacement, crossing = flags.crosses_open_face;
  long long nonfinite = flags.nonfinite, outside = flags.outside;
  double largest_d2 = flags.max_displacement2;
#pragma omp for schedule(dynamic, 1)
  for (std::size_t bi = 0; bi < blocks.size(); ++bi) {
    const std::size_t b = blocks[bi];
    const double block_start = block_seconds ? omp_get_wtime() : 0.0;
    ParticleStencil<Shape> stencil;
    HalfWidths<Shape> half_widths(1.0 / g.h);
    RecordGather<kNodeRecord, kForceSlot> dv_gather(records);              // v^L - v
    RecordGather<kLagrangianRecord, 0> vl_gather(grid.lagrangian_records());  // v^L
    RecordScatter<false, true, false> remap_scatter;
    static constexpr double kNoStress[6] = {0, 0, 0, 0, 0, 0};
    const auto origin = sort.block_origin(b);
    double* remap_records = records;
    BoxTarget box;  // with into_boxes: the block's box, which the remap scatters into
    if constexpr (into_boxes) {
      remap_records = buffers->open_box(b);
      box = {buffers->first_node(b), buffers->edge()};
    }
    double damped = 0.0;       // kinetic energy the PIC share removed in this block
    double incremented = 0.0;  // the block's kinetic energy of the FLIP increments (increment_kinetic)
    for (std::size_t p = sort.block_begin(b); p < sort.block_end(b); ++p) {
      double hw[3];
      half_widths(P, p, hw);
      bool finite = true;
      stencil.visit(grid, terrain, P.x[0][p], P.x[1][p], P.x[2][p], hw, [&](const auto& s) {
        constexpr int N = std::decay_t<decltype(s)>::N;
        double dvp[3], vlp[3];
        // Sum factorisation: N = wx wy wz, so each (a, b) row sums wz-weighted values first.
        dv_gather.start_particle();
        vl_gather.start_particle();
        for (int a = 0; a < N; ++a)
          for (int bb = 0; bb < N; ++bb) {
            const std::size_t row = s.ix[a] + s.iy[bb];
            dv_gather.start_row();
            vl_gather.start_row();
            for (int c = 0; c < N; ++c) {
              const std::size_t n = row + s.iz[c];
              dv_gather.add_node(n, s.wz[c]);
              vl_gather.add_node(n, s.wz[c]);
            }
            const double wxy = s.wx[a] * s.wy[bb];
            dv_gather.end_row(wxy);
            vl_gather.end_row(wxy);
          }
        dv_gather.value(dvp);
        vl_gather.value(vlp);
        if (increment_kinetic) [[unlikely]]
          incremented += 0.5 * P.mass[p] * (dvp[0] * dvp[0] + dvp[1] * dvp[1] + dvp[2] * dvp[2]);
        if (pic_fraction > 0.0) {
          // v_p = (1 - beta) (v_p + sum N dv) + beta sum N v^L: the PIC share beta damps the particle
          // velocity's part that the grid cannot represent; the kinetic energy it removes is counted
          double before = 0.0, after = 0.0;
          for (int d = 0; d < 3; ++d) {
            const double flip = P.v[d][p] + dvp[d];
            const double blended = (1.0 - pic_fraction) * flip + pic_fraction * vlp[d];
            before += flip * flip;
            after += blended * blended;
            dvp[d] = blended - P.v[d][p];
          }
          damped += 0.5 * P.mass[p] * (before - after);
        }
        for (int d = 0; d < 3; ++d) {
          P.v[d][p] += dvp[d];       // Edo & Matsubara 2015, eq. 50: v_p += dt sum a_i N_i
          disp[d][p] = dt * vlp[d];  // Edo & Matsubara 2015, eq. 51: x_p += dt sum v_i^L N_i (applied later)
          finite = finite && std::isfinite(P.v[d][p]) && std::isfinite(disp[d][p]);
        }
        if constexpr (remap) {
          const double m = P.mass[p];
          const double mv[3] = {m * P.v[0][p], m * P.v[1][p], m * P.v[2][p]};
          remap_scatter.set_particle(m, mv, kNoStress);  // as scatter_to_grid's Momentum
          const auto remap_rows = [&](const std::size_t* ix, const std::size_t* iy, const std::size_t* iz) {
            for (int a = 0; a < N; ++a)
              for (int bb = 0; bb < N; ++bb) {
                const std::size_t row = ix[a] + iy[bb];
                remap_scatter.template set_row<false>(s.wx[a] * s.wy[bb], 0.0, 0.0, 0.0);
                for (int c = 0; c < N; ++c)
                  remap_scatter.add_to(remap_records + (row + iz[c]) * kNodeRecord, s.wz[c], 0.0);
              }
          };
          if constexpr (into_boxes)
            with_scatter_index(s, &box, remap_rows);
          else
            remap_rows(s.ix, s.iy, s.iz);
        }
      });
      bool inside = true;
      int cell[3];
      double next[3];
      for (int d = 0; d < 3; ++d) next[d] = P.x[d][p] + disp[d][p];
      // periodic axes: the position the solver wraps it to after the move (Solver::wrap_periodic)
      if (g.has_periodic_axes()) [[unlikely]]
        for (int d = 0; d < 2; ++d) next[d] = g.wrap_position(d, next[d]);
      // the next step's cell in (x, y, w): the same map as the stencil and the cell sort
      if constexpr (!Terrain::kIsFlat) next[2] -= terrain.height(next[0]);
      for (int d = 0; d < 3; ++d) {
        cell[d] = g.cell_of(d, next[d]);
        // The support of the next step must stay inside the padded arrays.
        inside = inside && cell[d] - Shape::kReachLow >= 0 && cell[d] + Shape::kReachHigh < nodes[d];
      }
      // After the move x_p = x_p + displacement: exactly next[] (the same sum, then wrapped), in (x, y, w).
      // A particle past an open face leaves with this step (Solver::remove_outflow) and needs no next
      // support: with guards.max_step_displacement above 1 cell a wide shape's support could pass the
      // padded arrays there, and the step stopped with "left the grid" instead of counting the outflow.
      const bool leaving = options.beyond_open_face(next);
      inside = inside || leaving;
      crossing = crossing || leaving;
      const double d2 = disp[0][p] * disp[0][p] + disp[1][p] * disp[1][p] + disp[2][p] * disp[2][p];
      large = large || d2 > max_d2;
      largest_d2 = d2 > largest_d2 ? d2 : largest_d2;  // a NaN is reported as nonfinite instead
      if (!finite) nonfinite = std::max(nonfinite, static_cast<long long>(p));
      if (!inside) outside = std::max(outside, static_cast<long long>(p));
      if (!sort.within_slack_of(origin, cell[0], cell[1], cell[2])) needs_sort = true;
    }
    if constexpr (into_boxes) buffers->close_box(b, box.lo, box.hi);
    if (pic_fraction > 0.0) block_damping[b] = damped;
    if (increment_kinetic) (*increment_kinetic)[b] = incremented;
    if (block_seconds) (*block_seconds)[bi] = omp_get_wtime() - block_start;
  }
  flags = {needs_sort, nonfinite, outside, large, crossing, largest_d2};
}

}  // namespace

template <class Shape, class Terrain>
GatherResult gather_impl(ParticleStore& P, const CellSort& sort, Grid& grid,
                         const std::array<std::span<double>, 3>& displacement, std::vector<double>& block_damping,
                         const GatherOptions& options, BlockBuffers* buffers, ColourPassTiming* timing) {
  GatherResult result;
  const bool one_pass = !options.remap || buffers;
  if (timing) {
    if (one_pass)
      timing->block_seconds[0].assign(sort.block_count(), 0.0);
    else
      for (int colour = 0; colour < 8; ++colour) timing->block_seconds[colour].assign(sort.colour(colour).size(), 0.0);
  }
  double pass_start = timing ? omp_get_wtime() : 0.0;
#pragma omp parallel
  {
    GatherResult mine;
    if (one_pass) {
      // one pass over all blocks (a pure gather, or the remap into the blocks' boxes: any order);
      // a timing record lists it as colour 0
      const std::vector<std::uint32_t>& order = sort.blocks_in_work_order();
      std::vector<double>* seconds = timing ? &timing->block_seconds[0] : nullptr;
      if (!options.remap)
        gather_blocks<Shape, Terrain, false, false>(P, sort, grid, displacement, block_damping, options, order, mine,
                                                    seconds, nullptr);
      else
        gather_blocks<Shape, Terrain, true, true>(P, sort, grid, displacement, block_damping, options, order, mine,
                                                  seconds, buffers);
      if (timing) {
#pragma omp master
        timing->wall[0] = omp_get_wtime() - pass_start;
      }
    } else {
      // The remap scatters, so the blocks go colour by colour as in scatter_to_grid (one parallel
      // region, a barrier after each colour): each node sums its particles in the same order for any
      // thread count.
      for (int colour = 0; colour < 8; ++colour) {
        gather_blocks<Shape, Terrain, true, false>(P, sort, grid, displacement, block_damping, options,
                                                   sort.colour(colour), mine,
                                                   timing ? &timing->block_seconds[colour] : nullptr, nullptr);
        if (timing) {
#pragma omp master
          {
            const double now = omp_get_wtime();
            timing->wall[colour] = now - pass_start;
            pass_start = now;
          }
        }
      }
    }
#pragma omp critical(talus_gather_flags)
    {
      result.needs_sort = result.needs_sort || mine.needs_sort;
      result.large_displacement = result.large_displacement || mine.large_displacement;
      result.crosses_open_face = result.crosses_open_face || mine.crosses_open_face;
      result.nonfinite = std::max(result.nonfinite, mine.nonfinite);
      result.outside = std::max(result.outside, mine.outside);
      result.max_displacement2 = std::max(result.max_displacement2, mine.max_displacement2);  // any order: same bits
    }
  }
  return result;
}

namespace {

/// The velocity gradient's sums for the strain pass (Stencil::gradient, sum-factorised): per (a, b)
/// row S_i = sum_c v_i wz[c] and G_i = sum_c v_i gz[c], then L_i. += (gxy S_i - slope wxy G_i,
/// wgy S_i, wxy G_i). Two implementations with one interface: node velocities in plain arrays of a
/// given stride (scalar), and the records' momentum slots (vectors; every lane does the scalar
/// operations in their order, so the three velocity lanes get the same bits).
template <std::size_t kStride>
class StridedVelocityGradient {
 public:
  explicit StridedVelocityGradient(const NodeVectors& nv) : velocity_{nv[0].data(), nv[1].data(), nv[2].data()} {}
  void start_particle() {
    for (auto& row : L_) row[0] = row[1] = row[2] = 0.0;
  }
  void start_row() {
    for (int i = 0; i < 3; ++i) sw_[i] = sg_[i] = 0.0;
  }
  void add_node(std::size_t n, double wz, double gz) {
    for (int i = 0; i < 3; ++i) {
      const double vi = velocity_[i][n * kStride];
      sw_[i] += vi * wz;
      sg_[i] += vi * gz;
    }
  }
  template <bool kTerrain>
  void end_row(double gxy, double wgy, double wxy, double slope) {
    for (int i = 0; i < 3; ++i) {
      double dx = gxy * sw_[i];
      const double dz = wxy * sg_[i];
      if constexpr (kTerrain) dx -= slope * dz;  // dN/dx_phys = dN/dx - z_b' dN/dw
      L_[i][0] += dx;
      L_[i][1] += wgy * sw_[i];
      L_[i][2] += dz;
    }
  }
  void gradient(double L[3][3]) const {
    for (int i = 0; i < 3; ++i)
      for (int j = 0; j < 3; ++j) L[i][j] = L_[i][j];
  }

 private:
  const double* velocity_[3];
  double sw_[3], sg_[3], L_[3][3];
};

template <int kStride, int kSlot>
class RecordVelocityGradient {
  using Slots = RecordSlots<kStride, kSlot>;
  using D = typename Slots::D;
  using V = typename Slots::V;
  static constexpr int kParts = Slots::kParts, kLanes = Slots::kLanes;

 public:
  explicit RecordVelocityGradient(const double* records) : slots_(records) {}
  void start_particle() {
    for (int i = 0; i < kParts; ++i) lx_[i] = ly_[i] = lz_[i] = hn::Zero(D());
  }
  void start_row() {
    for (int i = 0; i < kParts; ++i) sw_[i] = sg_[i] = hn::Zero(D());
  }
  void add_node(std::size_t n, double wz, double gz) {
    const V w = hn::Set(D(), wz), g = hn::Set(D(), gz);
    for (int i = 0; i < kParts; ++i) {
      const V v = slots_.load(n, i);
      sw_[i] = hn::Add(sw_[i], hn::Mul(v, w));
      sg_[i] = hn::Add(sg_[i], hn::Mul(v, g));
    }
  }
  template <bool kTerrain>
  void end_row(double gxy, double wgy, double wxy, double slope) {
    const V gx = hn::Set(D(), gxy), wg = hn::Set(D(), wgy), w = hn::Set(D(), wxy);
    for (int i = 0; i < kParts; ++i) {
      V dx = hn::Mul(gx, sw_[i]);
      const V dz = hn::Mul(w, sg_[i]);
      if constexpr (kTerrain) dx = hn::Sub(dx, hn::Mul(hn::Set(D(), slope), dz));
      lx_[i] = hn::Add(lx_[i], dx);
      ly_[i] = hn::Add(ly_[i], hn::Mul(wg, sw_[i]));
      lz_[i] = hn::Add(lz_[i], dz);
    }
  }
  void gradient(double L[3][3]) const {
    alignas(64) double x[kParts * kLanes], y[kParts * kLanes], z[kParts * kLanes];
    for (int i = 0; i < kParts; ++i) {
      hn::Store(lx_[i], D(), x + i * kLanes);
      hn::Store(ly_[i], D(), y + i * kLanes);
      hn::Store(lz_[i], D(), z + i * kLanes);
    }
    for (int i = 0; i < 3; ++i) {
      const int lane = Slots::lane_of(i);
      L[i][0] = x[lane];
      L[i][1] = y[lane];
      L[i][2] = z[lane];
    }
  }

 private:
  Slots slots_;
  V sw_[kParts], sg_[kParts], lx_[kParts], ly_[kParts], lz_[kParts];
};

template <class Shape, class Terrain, class Gradient>
void strain_loop(const ParticleStore& P, const Grid& grid, Gradient gradient,
                 double dt, std::size_t begin, std::size_t end, StrainIncrements& out) {
  const Terrain& terrain = grid.template terrain<Terrain>();
  const double h = grid.geometry().h;
  ParticleStencil<Shape> stencil;
  HalfWidths<Shape> half_widths(1.0 / h);
  for (std::size_t p = begin; p < end; ++p) {
    double hw[3];
    half_widths(P, p, hw);
    double L[3][3];  // L_ij = dv_i / dx_j
    stencil.visit(grid, terrain, P.x[0][p], P.x[1][p], P.x[2][p], hw, [&](const auto& s) {
      constexpr int N = std::decay_t<decltype(s)>::N;
      gradient.start_particle();
      for (int a = 0; a < N; ++a)
        for (int bb = 0; bb < N; ++bb) {
          const std::size_t row = s.ix[a] + s.iy[bb];
          gradient.start_row();
          for (int c = 0; c < N; ++c) gradient.add_node(row + s.iz[c], s.wz[c], s.gz[c]);
          gradient.template end_row<!Terrain::kIsFlat>(s.gx[a] * s.wy[bb], s.wx[a] * s.gy[bb], s.wx[a] * s.wy[bb],
                                                       s.terrain_slope);
        }
      gradient.gradient(L);
    });
    const std::size_t k = p - begin;
    // Edo & Matsubara 2015, eq. 33: d_eps = dt/2 (L + L^T); spin dW = dt/2 (L - L^T)
    out.strain[XX][k] = dt * L[0][0];
    out.strain[YY][k] = dt * L[1][1];
    out.strain[ZZ][k] = dt * L[2][2];
    out.strain[YZ][k] = 0.5 * dt * (L[1][2] + L[2][1]);
    out.strain[XZ][k] = 0.5 * dt * (L[0][2] + L[2][0]);
    out.strain[XY][k] = 0.5 * dt * (L[0][1] + L[1][0]);
    out.spin[0][k] = 0.5 * dt * (L[1][2] - L[2][1]);
    out.spin[1][k] = 0.5 * dt * (L[0][2] - L[2][0]);
    out.spin[2][k] = 0.5 * dt * (L[0][1] - L[1][0]);
  }
}

}  // namespace

template <class Shape, class Terrain>
void strain_impl(const ParticleStore& P, const Grid& grid, const NodeVectors& nv,
                 double dt, std::size_t begin, std::size_t end, StrainIncrements& out) {
  auto strides_are = [&nv](std::size_t stride) {
    return nv[0].stride() == stride && nv[1].stride() == stride && nv[2].stride() == stride;
  };
  const bool remapped = strides_are(kNodeRecord) && nv[0].data() == grid.records() + kMomentumSlot &&
                        nv[1].data() == nv[0].data() + 1 && nv[2].data() == nv[0].data() + 2;
  const bool lagrangian = strides_are(kLagrangianRecord) && nv[0].data() == grid.lagrangian_records() &&
                          nv[1].data() == nv[0].data() + 1 && nv[2].data() == nv[0].data() + 2;
  if (remapped)  // v after the MUSL remap: the node records' momentum slots
    strain_loop<Shape, Terrain>(P, grid, RecordVelocityGradient<kNodeRecord, kMomentumSlot>(grid.records()), dt, begin,
                                end, out);
  else if (lagrangian)  // v^L (USL), the start velocities (USF, USAVG)
    strain_loop<Shape, Terrain>(P, grid, RecordVelocityGradient<kLagrangianRecord, 0>(grid.lagrangian_records()), dt,
                                begin, end, out);
  else if (strides_are(1))
    strain_loop<Shape, Terrain>(P, grid, StridedVelocityGradient<1>(nv), dt, begin, end, out);
  else
    throw std::logic_error("strain_increments: node velocities of mixed strides");
}
}  // namespace HWY_NAMESPACE
}  // namespace talus
HWY_AFTER_NAMESPACE();

#endif  // per-target include guard
