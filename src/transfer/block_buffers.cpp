#include "talus/transfer/block_buffers.hpp"

#include "talus/core/slice_offsets.hpp"

#include <omp.h>

#include <algorithm>
#include <atomic>
#include <stdexcept>

namespace talus {

void BlockBuffers::prepare(const CellSort& sort, const Grid& grid) {
  if (grid.geometry().has_periodic_axes())
    throw std::logic_error("BlockBuffers: periodic axes are not supported (the scene refuses them)");
  const double start = omp_get_wtime();
  below_ = sort.slack() + sort.reach_low();
  edge_ = sort.block_cells() + 2 * sort.slack() + sort.reach_low() + sort.reach_high();
  box_doubles_ = static_cast<std::size_t>(edge_) * edge_ * edge_ * kNodeRecord;
  const std::size_t count = sort.block_count();
  block_origin_.resize(count);
  for (std::size_t b = 0; b < count; ++b) block_origin_[b] = sort.block_origin(b);
  written_.assign(count, {0, 0, 0, 0, 0, 0});
  stale_.assign(count, 1);
  if (count * box_doubles_ > capacity_) {  // the scatter clears each box before it writes it
    capacity_ = count * box_doubles_ + count * box_doubles_ / 4;  // room for the flow to spread
    data_.reset(static_cast<double*>(::operator new[](capacity_ * sizeof(double), std::align_val_t(64))));
  }

  // Every (tile, block) pair whose box overlaps the tile, in tile order and, within a tile, in
  // ascending block order: each node then adds its boxes in ascending block order. Built in
  // parallel as a counting sort over the grid's active tiles (the tiles the boxes overlap): each
  // thread takes a contiguous range of blocks and counts its pairs per tile; a prefix sum over
  // (tile, thread) places them; each thread then writes its pairs in block order. The threads'
  // ranges ascend, so a tile's blocks do: the order a stable sort by tile of the block-ordered
  // pairs gives (the serial way, kept for a tile outside the active list, which does not occur).
  const auto tiles = grid.tiles();
  const std::vector<std::uint32_t>& active = grid.active_tiles();
  const std::size_t n_active = active.size();
  auto for_each_tile = [&](std::size_t b, auto&& f) {
    const auto first = first_node(b);
    std::array<int, 3> lo{}, hi{};
    for (int d = 0; d < 3; ++d) {
      lo[d] = std::max(first[d], 0) / kTileEdge;
      hi[d] = std::min((first[d] + edge_ - 1) / kTileEdge, tiles[d] - 1);
    }
    for (int ti = lo[0]; ti <= hi[0]; ++ti)
      for (int tj = lo[1]; tj <= hi[1]; ++tj)
        for (int tk = lo[2]; tk <= hi[2]; ++tk) f(static_cast<std::uint32_t>((static_cast<std::size_t>(ti) * tiles[1] + tj) * tiles[2] + tk));
  };
  auto active_index = [&](std::uint32_t tile) {
    return static_cast<std::size_t>(std::lower_bound(active.begin(), active.end(), tile) - active.begin());
  };
  struct Overlap {
    std::uint32_t tile, block;
  };
  std::vector<Overlap> overlaps;
  tile_counts_.resize(static_cast<std::size_t>(omp_get_max_threads()) * n_active);
  std::vector<std::uint32_t> tile_first(n_active + 1, 0);  // each tile's first pair
  std::atomic<bool> outside{false};
  double prefix_seconds = 0.0;
  serial_seconds_ = omp_get_wtime() - start;
#pragma omp parallel
  {
    const auto threads = static_cast<std::size_t>(omp_get_num_threads()), me = static_cast<std::size_t>(omp_get_thread_num());
    const std::size_t b0 = count * me / threads, b1 = count * (me + 1) / threads;
    std::uint32_t* const mine = tile_counts_.data() + me * n_active;  // per tile: my count, then my next slot
    std::fill_n(mine, n_active, 0u);
    for (std::size_t b = b0; b < b1; ++b)
      for_each_tile(b, [&](std::uint32_t tile) {
        const std::size_t i = active_index(tile);
        if (i == n_active || active[i] != tile)
          outside.store(true, std::memory_order_relaxed);
        else
          ++mine[i];
      });
    slice_offsets_in_region(tile_counts_.data(), threads, n_active, tile_first.data(), [&] {
      if (!outside.load(std::memory_order_relaxed)) overlaps.resize(tile_first[n_active]);
    }, &prefix_seconds);
    if (!outside.load(std::memory_order_relaxed)) {  // the same for every thread (read after the barriers)
      for (std::size_t b = b0; b < b1; ++b)
        for_each_tile(b, [&](std::uint32_t tile) {
          overlaps[mine[active_index(tile)]++] = {tile, static_cast<std::uint32_t>(b)};
        });
    }
  }
  serial_seconds_ += prefix_seconds;
  if (outside) {  // not expected: the serial way, block-ordered pairs sorted stably by tile
    const double serial_start = omp_get_wtime();
    overlaps.clear();
    for (std::size_t b = 0; b < count; ++b)
      for_each_tile(b, [&](std::uint32_t tile) { overlaps.push_back({tile, static_cast<std::uint32_t>(b)}); });
    std::stable_sort(overlaps.begin(), overlaps.end(), [](const Overlap& a, const Overlap& b) { return a.tile < b.tile; });
    serial_seconds_ += omp_get_wtime() - serial_start;
  }
  // Each pair's runs: rows along k of the nodes that its box shares with its tile. Counted, placed
  // by a prefix sum and written in parallel (the serial version was most of a sort's serial
  // bookkeeping with block buffers: ~0.2 ms for the default flume), in the same order as serially.
  const std::size_t pairs = overlaps.size();
  struct Span {
    int lo[3], hi[3];
  };
  std::vector<Span> spans(pairs);
  std::vector<std::size_t> offset(pairs + 1, 0);
#pragma omp parallel for schedule(static)
  for (std::size_t e = 0; e < pairs; ++e) {
    const std::array<int, 3> t0 = grid.node_of(overlaps[e].tile);  // the tile's first node
    const auto first = first_node(overlaps[e].block);
    Span& sp = spans[e];
    for (int d = 0; d < 3; ++d) {
      sp.lo[d] = std::max(t0[d], first[d]);
      sp.hi[d] = std::min(t0[d] + kTileEdge, first[d] + edge_);
    }
    // (an empty extent on any axis gives no runs, as the loops below would write none)
    const int rows_i = std::max(sp.hi[0] - sp.lo[0], 0), rows_j = std::max(sp.hi[1] - sp.lo[1], 0);
    offset[e + 1] = sp.hi[2] <= sp.lo[2] ? 0 : static_cast<std::size_t>(rows_i) * rows_j;
  }
  const double prefix_start = omp_get_wtime();
  tile_starts_.clear();
  tiles_.clear();
  for (std::size_t e = 0; e < pairs; ++e) {
    if (e == 0 || overlaps[e].tile != overlaps[e - 1].tile) {
      tile_starts_.push_back(static_cast<std::uint32_t>(offset[e]));
      tiles_.push_back(overlaps[e].tile);
    }
    offset[e + 1] += offset[e];
  }
  covers_active_tiles_ = tiles_ == grid.active_tiles();
  runs_.resize(offset[pairs]);  // keeps its memory from sort to sort
  serial_seconds_ += omp_get_wtime() - prefix_start;
  const std::size_t box_nodes = box_doubles_ / kNodeRecord;
#pragma omp parallel for schedule(static)
  for (std::size_t e = 0; e < pairs; ++e) {
    const std::size_t b = overlaps[e].block;
    const auto first = first_node(b);
    const Span& sp = spans[e];
    if (sp.hi[2] <= sp.lo[2]) continue;
    std::size_t r = offset[e];
    for (int i = sp.lo[0]; i < sp.hi[0]; ++i)
      for (int j = sp.lo[1]; j < sp.hi[1]; ++j)
        runs_[r++] = {grid.node(i, j, sp.lo[2]),
                      b * box_nodes + (static_cast<std::size_t>(i - first[0]) * edge_ + (j - first[1])) * edge_ +
                          (sp.lo[2] - first[2]),
                      static_cast<std::uint32_t>(b), static_cast<std::uint16_t>(sp.hi[2] - sp.lo[2]),
                      static_cast<std::int16_t>(i - first[0]), static_cast<std::int16_t>(j - first[1]),
                      static_cast<std::int16_t>(sp.lo[2] - first[2])};
  }
  tile_starts_.push_back(static_cast<std::uint32_t>(runs_.size()));
}

namespace {

/// Tile group g's runs added into the grid, in ascending block order: every node receives its boxes
/// in ascending block order, whichever thread holds the tile. Cleared first, the tile starts from
/// zeros as after Grid::clear_active, so the sums have the same bits.
template <bool kMass, bool kMomentum, bool kForce>
void add_tile_runs(const double* boxes, const auto& runs, const std::vector<std::uint32_t>& starts,
                   const std::vector<std::uint32_t>& tiles, const std::vector<std::array<int, 6>>& written, Grid& grid,
                   bool clear_first, std::size_t g) {
  double* const records = grid.records();
  if (clear_first) grid.clear_tile(tiles[g]);
  for (std::size_t e = starts[g]; e < starts[g + 1]; ++e) {
    // Only the nodes the box's scatter wrote (the others hold zeros: adding them changes nothing,
    // as no sum here is ever -0).
    const auto& run = runs[e];
    const auto& w = written[run.block];
    if (run.i < w[0] || run.i >= w[3] || run.j < w[1] || run.j >= w[4]) continue;
    const int k0 = std::max<int>(run.k, w[2]), k1 = std::min<int>(run.k + run.nodes, w[5]);
    if (k1 <= k0) continue;
    const double* from = boxes + (run.from + (k0 - run.k)) * kNodeRecord;
    double* to = records + (run.to + (k0 - run.k)) * kNodeRecord;
    const int nodes = k1 - k0;
    if constexpr (kMass && kMomentum && kForce) {
      for (int v = 0; v < nodes * kNodeRecord; ++v) to[v] += from[v];  // every slot (the unused one: zeros)
    } else {
      for (int n = 0; n < nodes; ++n, from += kNodeRecord, to += kNodeRecord) {
        if constexpr (kMass) to[kMassSlot] += from[kMassSlot];
        for (int d = 0; d < 3; ++d) {
          if constexpr (kMomentum) to[kMomentumSlot + d] += from[kMomentumSlot + d];
          if constexpr (kForce) to[kForceSlot + d] += from[kForceSlot + d];
        }
      }
    }
  }
}

}  // namespace

double* BlockBuffers::open_box(std::size_t b) {
  double* box = data_.get() + b * box_doubles_;
  if (stale_[b]) {
    std::fill_n(box, box_doubles_, 0.0);
    stale_[b] = 0;
    return box;
  }
  const auto& w = written_[b];
  if (w[2] < w[5])
    for (int i = w[0]; i < w[3]; ++i)
      for (int j = w[1]; j < w[4]; ++j)
        std::fill_n(box + ((static_cast<std::size_t>(i) * edge_ + j) * edge_ + w[2]) * kNodeRecord,
                    static_cast<std::size_t>(w[5] - w[2]) * kNodeRecord, 0.0);
  return box;
}

template <bool kMass, bool kMomentum, bool kForce>
TileStages::Stage BlockBuffers::tile_sum(Grid& grid, bool clear_first) const {
  return [this, &grid, clear_first](std::size_t g) {
    add_tile_runs<kMass, kMomentum, kForce>(data_.get(), runs_, tile_starts_, tiles_, written_, grid, clear_first, g);
  };
}

void BlockBuffers::add_sum_stage(TileStages& stages, Grid& grid, ScatteredFields f, bool clear_first) const {
  if (clear_first && !covers_active_tiles_)
    throw std::logic_error("BlockBuffers::add_sum_stage: the boxes do not cover the active tiles, which it would clear");
  TileStages::Stage stage;
  if (f.mass && f.momentum && f.force) stage = tile_sum<true, true, true>(grid, clear_first);
  else if (f.mass && f.momentum && !f.force) stage = tile_sum<true, true, false>(grid, clear_first);
  else if (!f.mass && f.momentum && !f.force) stage = tile_sum<false, true, false>(grid, clear_first);
  else if (!f.mass && !f.momentum && f.force) stage = tile_sum<false, false, true>(grid, clear_first);
  else throw std::logic_error("BlockBuffers::add_sum_stage: an unsupported set of fields");
  // Over the active tiles (the boxes' tiles are those): a tile's own nodes only, so the grid update
  // can follow on the same tile without a barrier. Otherwise a loop over the boxes' tiles of its own.
  if (covers_active_tiles_)
    stages.add(TileReach::OwnTile, std::move(stage));
  else
    stages.add_loop(tiles_.size(), std::move(stage));
}

}  // namespace talus
