#pragma once
// TileExchange: the nodes that several ranks of a distributed run write (docs/architecture.md,
// "Distributed runs").
//
// Each rank scatters its own particles onto its own copy of the grid, which commits only the tiles
// its particles may reach (Grid::active_tiles). A tile that two ranks both hold gets part of its
// sums on each: after P2G (and after the remap's scatter) every rank sends its values on the shared
// tiles to the ranks that share them, and each holder adds the parts of all holders IN RANK ORDER.
// Every holder then has the same bits, so the grid update, run on every active tile, gives the same
// velocities on both sides and no second message is needed (the "ghost velocities" are computed,
// not copied). Energies summed over nodes count a tile once: on its lowest-ranked holder.
//
// A tile this rank's particles did not reach (every field +0.0) is flagged, not sent: on the test
// collapse this cut the bytes a step by 65%, with the same bits.
//
// Which tiles are shared is found from the active tiles themselves, not from a fixed ghost width: a
// particle may stray past its slab until the next migration, and the tiles it reaches are still
// summed correctly. setup() runs after any rank's active tiles changed (a sort).
#include "talus/core/comm.hpp"
#include "talus/grid/grid.hpp"

#include <cstdint>
#include <vector>

namespace talus {

class TileExchange {
 public:
  /// Collective: find the tiles this rank shares with the others from every rank's active tiles.
  void setup(const Comm& comm, const Grid& grid);

  /// Collective: replace each of `fields` on the shared tiles by the sum over their holders, added
  /// in rank order. Returns the bytes this rank sent.
  std::size_t sum_shared(const Comm& comm, const std::vector<NodeField>& fields) const;

  /// Per active tile (in Grid::active_tiles order): 1 where this rank counts the tile's node
  /// energies (no lower rank holds it). Empty in a serial run: every tile counts.
  const std::vector<std::uint8_t>& counted() const { return counted_; }
  /// Shared tiles, summed over the peers (a tile shared with two peers counts twice).
  std::size_t shared_tiles() const;

 private:
  std::vector<int> peers_;                        // ranks sharing a tile with this one, ascending
  std::vector<std::vector<std::uint32_t>> shared_;  // per peer: the tiles both hold, ascending
  // The tiles shared with anyone, ascending, and for each its holders other than this rank: (peer
  // index, position in that peer's list), peers ascending.
  struct Holder {
    std::uint32_t peer, position;
  };
  std::vector<std::uint32_t> union_tiles_;
  std::vector<std::uint32_t> holder_start_;  // union_tiles_.size() + 1 offsets into holders_
  std::vector<Holder> holders_;
  int rank_ = 0;
  std::vector<std::uint8_t> counted_;
};

}  // namespace talus
