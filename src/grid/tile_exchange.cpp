#include "talus/grid/tile_exchange.hpp"

#include <algorithm>
#include <cmath>
#include <array>
#include <limits>

namespace talus {

void TileExchange::setup(const Comm& comm, const Grid& grid) {
  peers_.clear();
  shared_.clear();
  union_tiles_.clear();
  holder_start_.assign(1, 0);
  holders_.clear();
  counted_.clear();
  rank_ = comm.rank();
  if (!comm.distributed()) return;
  const std::vector<std::uint32_t>& active = grid.active_tiles();  // ascending (CellSort)
  // The x-range of tile columns each rank holds: only ranks whose ranges overlap can share a tile.
  const std::size_t column = static_cast<std::size_t>(grid.tiles()[1]) * grid.tiles()[2];
  std::array<std::int64_t, 2> range{std::numeric_limits<std::int64_t>::max(), -1};
  if (!active.empty()) range = {static_cast<std::int64_t>(active.front() / column), static_cast<std::int64_t>(active.back() / column)};
  const auto ranges = comm.allgather(range);
  std::vector<std::vector<unsigned char>> lists;
  for (int r = 0; r < comm.size(); ++r) {
    if (r == rank_ || ranges[r][1] < range[0] || ranges[r][0] > range[1]) continue;
    peers_.push_back(r);
    // my active tiles in the peer's column range (tile ids ascend with their column)
    const auto first = std::lower_bound(active.begin(), active.end(), static_cast<std::uint32_t>(ranges[r][0] * column));
    const auto last = std::upper_bound(active.begin(), active.end(), static_cast<std::uint32_t>((ranges[r][1] + 1) * column - 1));
    std::vector<unsigned char> bytes;
    append_bytes(bytes, &*first, static_cast<std::size_t>(last - first));
    lists.push_back(std::move(bytes));
  }
  const auto received = comm.exchange(peers_, lists);
  for (std::size_t i = 0; i < peers_.size(); ++i) {
    std::vector<std::uint32_t> theirs(received[i].size() / sizeof(std::uint32_t));
    ByteReader(received[i]).read(theirs.data(), theirs.size());
    std::vector<std::uint32_t> both;
    std::set_intersection(active.begin(), active.end(), theirs.begin(), theirs.end(), std::back_inserter(both));
    shared_.push_back(std::move(both));
  }
  // Drop the peers that share nothing; the list stays symmetric (the intersection is).
  std::vector<int> peers;
  std::vector<std::vector<std::uint32_t>> shared;
  for (std::size_t i = 0; i < peers_.size(); ++i)
    if (!shared_[i].empty()) {
      peers.push_back(peers_[i]);
      shared.push_back(std::move(shared_[i]));
    }
  peers_ = std::move(peers);
  shared_ = std::move(shared);
  // The union of the shared tiles with their holders, peers ascending.
  struct Entry {
    std::uint32_t tile, peer, position;
  };
  std::vector<Entry> entries;
  for (std::size_t i = 0; i < peers_.size(); ++i)
    for (std::size_t j = 0; j < shared_[i].size(); ++j)
      entries.push_back({shared_[i][j], static_cast<std::uint32_t>(i), static_cast<std::uint32_t>(j)});
  std::sort(entries.begin(), entries.end(),
            [](const Entry& a, const Entry& b) { return a.tile < b.tile || (a.tile == b.tile && a.peer < b.peer); });
  for (const Entry& e : entries) {
    if (union_tiles_.empty() || union_tiles_.back() != e.tile) {
      if (!union_tiles_.empty()) holder_start_.push_back(static_cast<std::uint32_t>(holders_.size()));
      union_tiles_.push_back(e.tile);
    }
    holders_.push_back({e.peer, e.position});
  }
  if (!union_tiles_.empty()) holder_start_.push_back(static_cast<std::uint32_t>(holders_.size()));
  // A tile counts here unless a lower rank holds it too.
  counted_.assign(active.size(), 1);
  for (std::size_t u = 0; u < union_tiles_.size(); ++u) {
    const bool lower = peers_[holders_[holder_start_[u]].peer] < rank_;  // holders ascend by rank
    if (!lower) continue;
    const auto at = std::lower_bound(active.begin(), active.end(), union_tiles_[u]) - active.begin();
    counted_[static_cast<std::size_t>(at)] = 0;
  }
}

std::size_t TileExchange::sum_shared(const Comm& comm, const std::vector<NodeField>& fields) const {
  if (!comm.distributed()) return 0;
  const std::size_t nf = fields.size();
  // A tile this rank's particles did not reach holds +0.0 in every field: it is not sent, and the
  // holders add +0.0 for it, the same bits as if it had been (x + 0.0 is what they would compute).
  // Each message: one flag byte per shared tile (padded to 8 bytes, so the values stay aligned), then
  // the fields of the flagged tiles.
  auto untouched = [&](std::uint32_t t) {
    const std::size_t base = static_cast<std::size_t>(t) * kTileNodes;
    for (const NodeField& f : fields)
      for (int s = 0; s < kTileNodes; ++s)
        if (std::signbit(f[base + s]) || f[base + s] != 0.0) return false;
    return true;
  };
  std::vector<std::vector<unsigned char>> out(peers_.size());
  std::size_t sent = 0;
  for (std::size_t i = 0; i < peers_.size(); ++i) {
    const std::size_t n = shared_[i].size();
    std::vector<unsigned char> flags((n + 7) / 8 * 8, 0);
    std::size_t included = 0;
    for (std::size_t j = 0; j < n; ++j) included += flags[j] = untouched(shared_[i][j]) ? 0 : 1;
    out[i].reserve(n + included * nf * kTileNodes * sizeof(double));
    append_bytes(out[i], flags.data(), flags.size());
    for (std::size_t j = 0; j < n; ++j)
      if (flags[j])
        for (const NodeField& f : fields) {
          std::array<double, kTileNodes> tile;
          const std::size_t base = static_cast<std::size_t>(shared_[i][j]) * kTileNodes;
          for (int s = 0; s < kTileNodes; ++s) tile[s] = f[base + s];
          append_bytes(out[i], tile.data(), kTileNodes);
        }
    sent += out[i].size();
  }
  const auto in = comm.exchange(peers_, out);
  // Where each peer's values of its j-th shared tile start (null: not sent, it is all +0.0).
  std::vector<std::vector<const double*>> from(peers_.size());
  for (std::size_t i = 0; i < peers_.size(); ++i) {
    const std::size_t n = shared_[i].size();
    const unsigned char* flags = in[i].data();
    const double* values = reinterpret_cast<const double*>(in[i].data() + (n + 7) / 8 * 8);
    from[i].assign(n, nullptr);
    std::size_t at = 0;
    for (std::size_t j = 0; j < n; ++j)
      if (flags[j]) {
        from[i][j] = values + at;
        at += nf * kTileNodes;
      }
  }
  static constexpr std::array<double, kTileNodes> kZeros{};
  // Each holder adds the same parts in the same (rank) order: the same bits everywhere.
#pragma omp parallel for schedule(static)
  for (std::size_t u = 0; u < union_tiles_.size(); ++u) {
    const std::size_t base = static_cast<std::size_t>(union_tiles_[u]) * kTileNodes;
    for (std::size_t f = 0; f < nf; ++f) {
      const NodeField& field = fields[f];
      std::array<double, kTileNodes> mine, sum{};
      for (int s = 0; s < kTileNodes; ++s) mine[s] = field[base + s];
      bool mine_added = false;
      for (std::uint32_t h = holder_start_[u]; h < holder_start_[u + 1]; ++h) {
        const Holder& holder = holders_[h];
        if (!mine_added && peers_[holder.peer] > rank_) {
          for (int s = 0; s < kTileNodes; ++s) sum[s] += mine[s];
          mine_added = true;
        }
        const double* tile = from[holder.peer][holder.position];
        const double* theirs = tile ? tile + f * kTileNodes : kZeros.data();
        for (int s = 0; s < kTileNodes; ++s) sum[s] += theirs[s];
      }
      if (!mine_added)
        for (int s = 0; s < kTileNodes; ++s) sum[s] += mine[s];
      for (int s = 0; s < kTileNodes; ++s) field[base + s] = sum[s];
    }
  }
  return sent;
}

std::size_t TileExchange::shared_tiles() const {
  std::size_t n = 0;
  for (const auto& s : shared_) n += s.size();
  return n;
}

}  // namespace talus
