#pragma once
// MlsStoredWeights: the per-particle fits' weights Phi_I (Edo & Matsubara 2015, eq. 46) kept from
// one smoothing pass, so that later steps can smooth with them without fitting again (the
// `reused` variant, MlsVariant::Reused). Smoothing with the stored weights gives, bit for bit,
// what the particle fit gives at the positions the weights were fitted at: each particle's entries
// are its neighbours within the radius in the fit's candidate order, with the fit's Phi, and the
// sum runs in that order with the same operations (no fused multiply-add: -ffp-contract=off).
//
// Layout: each thread of the fit appends its particles' entries to segments of its own (fixed
// blocks of kSegmentEntries; a particle's entries never straddle two), and each particle keeps where
// its entries are and how many (none: the particle keeps its own increment, not fitted or stopped
// by the guard). Segments are not moved or grown once written: the weights take what they need
// plus the unused end of each segment, with no copy, and a later fit reuses them. A sort permutes
// the store: remap() carries the weights over through the particles' ids.
#include "talus/smoothing/mls_strain_smoother.hpp"

#include <array>
#include <cstddef>
#include <cstdint>
#include <memory>
#include <span>
#include <vector>

namespace talus {

class MlsStoredWeights {
 public:
  static constexpr std::size_t kSegmentEntries = std::size_t{1} << 16;  // 768 kB a segment

  /// Particle p's entries: its neighbours (store indices) and their Phi = W_I a^T F(u_I) (eq. 46).
  struct Entries {
    const std::uint32_t* neighbour;
    const double* phi;
    std::uint32_t count;
  };
  Entries entries(std::size_t p) const {
    const Segment* s = segment_[p];
    return s ? Entries{s->neighbour.get() + start_[p], s->phi.get() + start_[p], count_[p]}
             : Entries{nullptr, nullptr, 0};
  }

  bool empty() const { return count_.empty(); }
  std::size_t particle_count() const { return count_.size(); }
  std::size_t entry_count() const;
  std::size_t bytes() const;
  void clear() { count_.clear(), segment_.clear(), start_.clear(); }

  /// Start a fit of `particles` particles by up to `threads` threads: every particle has no entries.
  void begin_fit(std::size_t particles, int threads);
  /// After the fit: the segments no thread reached this time are freed.
  void end_fit();
  /// Particle p's entries, from thread `thread`: fill(neighbour, phi) writes at most `most` of
  /// them there, in order, and returns how many it wrote.
  template <class Fill>
  void add(int thread, std::uint32_t p, std::size_t most, Fill&& fill) {
    Segment& s = room(static_cast<std::size_t>(thread), most);
    const std::size_t written = fill(s.neighbour.get() + s.used, s.phi.get() + s.used);
    segment_[p] = &s;
    start_[p] = static_cast<std::uint32_t>(s.used);
    count_[p] = static_cast<std::uint32_t>(written);
    s.used += written;
  }

  /// out[c][p] = sum over p's entries of phi * in[c][neighbour] (eq. 45), or in[c][p] where p has
  /// none. Parallel over particles; the same bits for any thread count and on every path.
  /// `smooth_body` marks the particles the guard counts (MlsCounts::unsmoothed) when they keep their
  /// own. `rows` is scratch (the increments as rows of 8 doubles; kept by the caller between calls).
  MlsCounts apply(const std::array<const double*, 6>& in, const std::array<double*, 6>& out,
                  std::span<const std::uint16_t> body, const std::vector<std::uint8_t>& smooth_body,
                  std::vector<double>& rows) const;

  /// Carry the weights over a reordering of the store: `old_ids` are the particles' ids in the
  /// order the weights index, `new_ids` the ids now. Every particle keeps its entries (in their
  /// order), with its neighbours' new indices. Returns false, and clears the weights, where a
  /// particle of either order is missing from the other or an id repeats (the caller fits anew).
  bool remap(std::span<const std::int64_t> old_ids, std::span<const std::int64_t> new_ids);

  /// The entries in store order, as one list: particle p's are [offsets[p], offsets[p + 1]) (the
  /// checkpoint's form), and back. assign() refuses (returns false, and clears the weights) lists
  /// that are not such a form: offsets not starting at 0 or decreasing, lengths that disagree, or
  /// a neighbour beyond the particles.
  void flatten(std::vector<std::uint64_t>& offsets, std::vector<std::uint32_t>& neighbour,
               std::vector<double>& phi) const;
  bool assign(const std::vector<std::uint64_t>& offsets, const std::vector<std::uint32_t>& neighbour,
              const std::vector<double>& phi);

  MlsStoredWeights() = default;
  MlsStoredWeights(const MlsStoredWeights& other) { *this = other; }
  MlsStoredWeights& operator=(const MlsStoredWeights& other);
  MlsStoredWeights(MlsStoredWeights&&) = default;
  MlsStoredWeights& operator=(MlsStoredWeights&&) = default;

 private:
  struct Segment {  // allocated, not initialised (a fit writes what it uses): no zero-fill of its pages
    std::unique_ptr<std::uint32_t[]> neighbour;
    std::unique_ptr<double[]> phi;
    std::size_t size = 0;  // entries
    std::size_t used = 0;
  };
  struct Chunk {  // one thread's segments; `current` is the one it writes (npos: none yet in this fit)
    std::vector<std::unique_ptr<Segment>> segments;
    std::size_t current = static_cast<std::size_t>(-1);
  };
  Segment& room(std::size_t thread, std::size_t most);
  bool remap_or_refuse(std::span<const std::int64_t> old_ids, std::span<const std::int64_t> new_ids);
  std::vector<Chunk> chunks_;
  std::vector<const Segment*> segment_;  // per particle (null: no entries)
  std::vector<std::uint32_t> start_;     // per particle, in its segment
  std::vector<std::uint32_t> count_;     // per particle
};

}  // namespace talus
