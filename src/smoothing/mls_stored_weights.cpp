// The stored weights of the `reused` MLS variant: applied (eq. 45 with the kept Phi) and carried
// over a sort. The apply is compiled once per instruction set by Highway's foreach_target and
// dispatched at run time (core/simd_dispatch.hpp): a particle's six increments are one row of 8
// doubles (a vector of 8 on every path: one AVX-512 register, two AVX2 or four SSE2 registers), so
// each neighbour is one row load, one product and one sum. Lane c of the row is component c's sum,
// with the same multiplications and additions in the same order as the particle fit's pass 2 (no
// fused multiply-add: the build sets -ffp-contract=off): the same bits on every path.
#undef HWY_TARGET_INCLUDE
#define HWY_TARGET_INCLUDE "smoothing/mls_stored_weights.cpp"
#include <hwy/foreach_target.h>  // IWYU pragma: keep

#include <hwy/highway.h>

#include "talus/core/simd_dispatch.hpp"
#include "talus/smoothing/mls_stored_weights.hpp"

#include <algorithm>
#include <cstdint>
#include <limits>

// Lane vectors live only inside this file's inlined functions: no call passes one by value.
#pragma GCC diagnostic ignored "-Wpsabi"

HWY_BEFORE_NAMESPACE();
namespace talus {
namespace HWY_NAMESPACE {
namespace {
typedef double Row __attribute__((vector_size(8 * sizeof(double)), aligned(64), may_alias));
// How far ahead the entries are prefetched: 1 kB of each list (measured at a 2-cell radius).
constexpr std::uint32_t kPhiAhead = 128, kNeighbourAhead = 256;
}  // namespace

/// MlsStoredWeights::apply on this target: the increments copied into rows, then each
/// particle's sum over its entries.
MlsCounts ApplyStoredWeights(const MlsStoredWeights& weights, const std::array<const double*, 6>& in,
                             const std::array<double*, 6>& out, const std::uint16_t* body,
                             const std::vector<std::uint8_t>& smooth_body, double* rows_memory) {
  const std::int64_t n = static_cast<std::int64_t>(weights.particle_count());
  Row* rows = reinterpret_cast<Row*>(rows_memory);
  std::size_t smoothed = 0, unsmoothed = 0;
#pragma omp parallel reduction(+ : smoothed, unsmoothed)
  {
#pragma omp for schedule(static)
    for (std::int64_t p = 0; p < n; ++p) {
      Row r = {};
      for (int c = 0; c < 6; ++c) r[c] = in[c][p];
      rows[p] = r;
    }
#pragma omp for schedule(static)
    for (std::int64_t p = 0; p < n; ++p) {
      const MlsStoredWeights::Entries e = weights.entries(static_cast<std::size_t>(p));
      if (e.count == 0) {  // kept its own increment when the weights were fitted
        for (int c = 0; c < 6; ++c) out[c][p] = in[c][p];
        unsmoothed += smooth_body[body[p]] ? 1 : 0;
        continue;
      }
      // the particle fit's pass 2 (smoothing/mls_strain_smoother.cpp): sum += phi * in, in order.
      // The entries ahead (this particle's and the next ones', which follow in the segment) are
      // asked for without keeping them in the outer caches: read once a step, they would push out
      // the rows, which the neighbouring particles read again. Near a segment's end the hint points
      // past it: a prefetch never faults and reads nothing into the sums.
      Row sum = {};
      for (std::uint32_t k = 0; k < e.count; ++k) {
        if (k % 8 == 0) {
          __builtin_prefetch(e.phi + k + kPhiAhead, 0, 0);
          if (k % 16 == 0) __builtin_prefetch(e.neighbour + k + kNeighbourAhead, 0, 0);
        }
        sum += e.phi[k] * rows[e.neighbour[k]];
      }
      for (int c = 0; c < 6; ++c) out[c][p] = sum[c];
      ++smoothed;
    }
  }
  return {smoothed, unsmoothed};
}

}  // namespace HWY_NAMESPACE
}  // namespace talus
HWY_AFTER_NAMESPACE();

#if HWY_ONCE
namespace talus {

HWY_EXPORT(ApplyStoredWeights);


std::size_t MlsStoredWeights::entry_count() const {
  std::size_t n = 0;
  for (std::uint32_t c : count_) n += c;
  return n;
}

std::size_t MlsStoredWeights::bytes() const {
  std::size_t b = segment_.capacity() * sizeof(const Segment*) + start_.capacity() * sizeof(std::uint32_t) +
                  count_.capacity() * sizeof(std::uint32_t);
  for (const Chunk& c : chunks_)
    for (const auto& s : c.segments)
      b += s->size * (sizeof(std::uint32_t) + sizeof(double));
  return b;
}

void MlsStoredWeights::begin_fit(std::size_t particles, int threads) {
  const std::size_t t = static_cast<std::size_t>(std::max(threads, 1));
  if (chunks_.size() < t) chunks_.resize(t);
  for (Chunk& c : chunks_) c.current = static_cast<std::size_t>(-1);  // keep their segments
  segment_.assign(particles, nullptr);
  start_.assign(particles, 0);
  count_.assign(particles, 0);
}

MlsStoredWeights::Segment& MlsStoredWeights::room(std::size_t thread, std::size_t most) {
  Chunk& c = chunks_[thread];
  if (c.current < c.segments.size()) {
    Segment& s = *c.segments[c.current];
    if (s.used + most <= s.size) return s;
  }
  ++c.current;  // npos + 1 = 0: the first
  // The next segment of an earlier fit if it is large enough, or a new one in its place.
  if (c.current < c.segments.size() && c.segments[c.current]->size < most) c.segments.resize(c.current);
  if (c.current == c.segments.size()) {
    auto s = std::make_unique<Segment>();
    const std::size_t size = std::max(kSegmentEntries, most);
    s->neighbour = std::make_unique_for_overwrite<std::uint32_t[]>(size);
    s->phi = std::make_unique_for_overwrite<double[]>(size);
    s->size = size;
    c.segments.push_back(std::move(s));
  }
  Segment& s = *c.segments[c.current];
  s.used = 0;
  return s;
}

void MlsStoredWeights::end_fit() {
  for (Chunk& c : chunks_) c.segments.resize(c.current == static_cast<std::size_t>(-1) ? 0 : c.current + 1);
}

MlsStoredWeights& MlsStoredWeights::operator=(const MlsStoredWeights& other) {
  if (this == &other) return *this;
  std::vector<std::uint64_t> offsets;
  std::vector<std::uint32_t> neighbour;
  std::vector<double> phi;
  other.flatten(offsets, neighbour, phi);
  chunks_.clear();
  assign(offsets, neighbour, phi);  // a flattened store is always consistent
  return *this;
}

MlsCounts MlsStoredWeights::apply(const std::array<const double*, 6>& in, const std::array<double*, 6>& out,
                                  std::span<const std::uint16_t> body, const std::vector<std::uint8_t>& smooth_body,
                                  std::vector<double>& rows_memory) const {
  // The increments as rows of 8 doubles, 64-byte aligned: one row a particle.
  const std::size_t n = particle_count();
  if (rows_memory.size() < 8 * n + 8) rows_memory.assign(8 * n + 8, 0.0);
  const std::size_t misalign = reinterpret_cast<std::uintptr_t>(rows_memory.data()) % 64;
  double* rows = rows_memory.data() + (misalign ? (64 - misalign) / sizeof(double) : 0);
  // The `reference` path runs the baseline build of the same code.
  return (vector_kernels_enabled() ? HWY_DYNAMIC_DISPATCH(ApplyStoredWeights) : &HWY_STATIC_DISPATCH(ApplyStoredWeights))(
      *this, in, out, body.data(), smooth_body, rows);
}

namespace {

/// Match two orders of the same particles by id: old_of_new[p] is the old index of new particle p,
/// moved[o] the new index of old particle o. False where an id repeats or is in one order only.
/// Ids are dense in a run (0 .. seeded - 1, less the particles that left): indexed directly; others
/// are matched by sorting.
bool match_ids(std::span<const std::int64_t> old_ids, std::span<const std::int64_t> new_ids,
               std::vector<std::uint32_t>& old_of_new, std::vector<std::uint32_t>& moved) {
  const std::size_t n = new_ids.size();
  std::int64_t lo = 0, hi = -1;
  for (std::int64_t id : old_ids) {
    lo = std::min(lo, id);
    hi = std::max(hi, id);
  }
  constexpr std::uint32_t kNone = std::numeric_limits<std::uint32_t>::max();
  if (lo >= 0 && hi < static_cast<std::int64_t>(4 * n + 1024)) {
    std::vector<std::uint32_t> old_index(static_cast<std::size_t>(hi) + 1, kNone);
    for (std::size_t p = 0; p < n; ++p) {
      if (old_index[old_ids[p]] != kNone) return false;
      old_index[old_ids[p]] = static_cast<std::uint32_t>(p);
    }
    std::fill(moved.begin(), moved.end(), kNone);
    for (std::size_t p = 0; p < n; ++p) {
      const std::int64_t id = new_ids[p];
      if (id < 0 || id > hi || old_index[id] == kNone || moved[old_index[id]] != kNone) return false;
      old_of_new[p] = old_index[id];
      moved[old_index[id]] = static_cast<std::uint32_t>(p);
    }
    return true;
  }
  std::vector<std::pair<std::int64_t, std::uint32_t>> a(n), b(n);
  for (std::size_t p = 0; p < n; ++p) {
    a[p] = {old_ids[p], static_cast<std::uint32_t>(p)};
    b[p] = {new_ids[p], static_cast<std::uint32_t>(p)};
  }
  std::sort(a.begin(), a.end());
  std::sort(b.begin(), b.end());
  for (std::size_t i = 0; i < n; ++i) {
    if (a[i].first != b[i].first || (i > 0 && a[i].first == a[i - 1].first)) return false;
    old_of_new[b[i].second] = a[i].second;
    moved[a[i].second] = b[i].second;
  }
  return true;
}

}  // namespace

bool MlsStoredWeights::remap(std::span<const std::int64_t> old_ids, std::span<const std::int64_t> new_ids) {
  const bool ok = remap_or_refuse(old_ids, new_ids);
  if (!ok) clear();
  return ok;
}

bool MlsStoredWeights::remap_or_refuse(std::span<const std::int64_t> old_ids, std::span<const std::int64_t> new_ids) {
  const std::size_t n = new_ids.size();
  if (empty() || old_ids.size() != particle_count() || n != old_ids.size() ||
      n >= std::numeric_limits<std::uint32_t>::max())
    return false;
  if (std::equal(old_ids.begin(), old_ids.end(), new_ids.begin())) return true;  // the sort kept the order
  // old_of_new[p]: where particle p of the new order was; moved[o]: where particle o went.
  std::vector<std::uint32_t> old_of_new(n), moved(n);
  if (!match_ids(old_ids, new_ids, old_of_new, moved)) return false;
  // The neighbours' new indices, in place: the entries stay where they are.
  for (Chunk& c : chunks_)
    for (const auto& seg : c.segments) {
      const std::int64_t m = static_cast<std::int64_t>(seg->used);
      std::uint32_t* nb = seg->neighbour.get();
#pragma omp parallel for schedule(static)
      for (std::int64_t e = 0; e < m; ++e) nb[e] = moved[nb[e]];
    }
  // Each particle's (segment, start, count) moves with it.
  std::vector<const Segment*> segment(n);
  std::vector<std::uint32_t> start(n), count(n);
  for (std::size_t p = 0; p < n; ++p) {
    const std::uint32_t o = old_of_new[p];
    segment[p] = segment_[o];
    start[p] = start_[o];
    count[p] = count_[o];
  }
  segment_ = std::move(segment);
  start_ = std::move(start);
  count_ = std::move(count);
  return true;
}

void MlsStoredWeights::flatten(std::vector<std::uint64_t>& offsets, std::vector<std::uint32_t>& neighbour,
                               std::vector<double>& phi) const {
  const std::size_t n = particle_count();
  offsets.assign(n + 1, 0);
  for (std::size_t p = 0; p < n; ++p) offsets[p + 1] = offsets[p] + count_[p];
  neighbour.resize(offsets[n]);
  phi.resize(offsets[n]);
  for (std::size_t p = 0; p < n; ++p) {
    const Entries e = entries(p);
    std::copy_n(e.neighbour, e.count, neighbour.data() + offsets[p]);
    std::copy_n(e.phi, e.count, phi.data() + offsets[p]);
  }
}

bool MlsStoredWeights::assign(const std::vector<std::uint64_t>& offsets, const std::vector<std::uint32_t>& neighbour,
                              const std::vector<double>& phi) {
  const std::size_t n = offsets.empty() ? 0 : offsets.size() - 1;
  bool consistent = !offsets.empty() && offsets[0] == 0 && neighbour.size() == offsets.back() && phi.size() == offsets.back();
  for (std::size_t p = 1; consistent && p < offsets.size(); ++p) consistent = offsets[p] >= offsets[p - 1];
  for (std::size_t e = 0; consistent && e < neighbour.size(); ++e) consistent = neighbour[e] < n;
  if (!consistent) {
    clear();
    return false;
  }
  begin_fit(n, 1);
  for (std::size_t p = 0; p < n; ++p) {
    const std::size_t first = offsets[p], count = offsets[p + 1] - offsets[p];
    if (count == 0) continue;
    add(0, static_cast<std::uint32_t>(p), count, [&](std::uint32_t* nb, double* f) {
      std::copy_n(neighbour.data() + first, count, nb);
      std::copy_n(phi.data() + first, count, f);
      return count;
    });
  }
  end_fit();
  return true;
}

}  // namespace talus
#endif
