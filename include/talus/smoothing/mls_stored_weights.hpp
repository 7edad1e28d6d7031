#pragma once
// MlsStoredWeights: the per-particle fits' weights Phi_I (Edo & Matsubara 2015, eq. 45) kept from
// one smoothing pass, so that later steps can smooth with them without fitting again (the
// `reused` variant, MlsVariant::Reused). Smoothing with the stored weights gives, bit for bit,
// what the particle fit gives at the positions the weights were fitted at: each particle's entries
// are its neighbours within the radius in the fit's candidate order, with the fit's Phi, and the
// sum runs in that order with the same operations (no fused multiply-add: -ffp-contract=off).
//
// Layout: the threads of the fit append their particles' entries to chunks of their own; particle
// p's entries are count[p] entries from start[p] of chunk chunk[p] (none: the particle keeps its
// own increment, not fitted or stopped by the guard). The chunks keep their memory from one fit to
// the next, so a fit allocates nothing once the first has run. A sort permutes the store: remap()
// carries the weights over through the particles' ids.
#include "talus/smoothing/mls_strain_smoother.hpp"

#include <algorithm>
#include <array>
#include <cstddef>
#include <cstdint>
#include <span>
#include <vector>

namespace talus {

class MlsStoredWeights {
 public:
  struct Chunk {
    std::vector<std::uint32_t> neighbour;  // store indices
    std::vector<double> phi;               // W_I a^T F(u_I), eq. 45
    std::size_t used = 0;                  // entries written (the vectors may be longer)
  };

  bool empty() const { return count_.empty(); }
  std::size_t particle_count() const { return count_.size(); }
  std::size_t entry_count() const;
  std::size_t bytes() const;
  void clear() { count_.clear(); }

  /// Start a fit of `particles` particles by up to `threads` threads: every particle has no entries.
  void begin_fit(std::size_t particles, int threads);
  /// After the fit: a chunk that holds room for more than 1.25 times its entries (the first
  /// fit's growth) is copied into room for 1.1 times, so that the weights take about what they
  /// need; later fits of a similar size then allocate nothing.
  void end_fit();
  /// Particle p's entries, from thread `thread`: fill(neighbour, phi) writes at most `most` of
  /// them there, in order, and returns how many it wrote.
  template <class Fill>
  void add(int thread, std::uint32_t p, std::size_t most, Fill&& fill) {
    Chunk& c = chunks_[static_cast<std::size_t>(thread)];
    if (c.neighbour.size() < c.used + most) {
      const std::size_t room = std::max(2 * c.neighbour.size(), c.used + most);
      c.neighbour.resize(room);
      c.phi.resize(room);
    }
    const std::size_t written = fill(c.neighbour.data() + c.used, c.phi.data() + c.used);
    count_[p] = static_cast<std::uint32_t>(written);
    chunk_[p] = static_cast<std::uint16_t>(thread);
    start_[p] = c.used;
    c.used += written;
  }

  /// out[c][p] = sum over p's entries of phi * in[c][neighbour] (eq. 46), or in[c][p] where p has
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
  /// checkpoint's form), and back.
  void flatten(std::vector<std::uint64_t>& offsets, std::vector<std::uint32_t>& neighbour,
               std::vector<double>& phi) const;
  void assign(std::vector<std::uint64_t> offsets, std::vector<std::uint32_t> neighbour, std::vector<double> phi);

 private:
  bool remap_or_refuse(std::span<const std::int64_t> old_ids, std::span<const std::int64_t> new_ids);
  std::vector<Chunk> chunks_;
  std::vector<std::uint16_t> chunk_;  // per particle
  std::vector<std::uint64_t> start_;  // per particle, in its chunk
  std::vector<std::uint32_t> count_;  // per particle
};

}  // namespace talus
