#include "talus/particles/cell_sort.hpp"

#include "talus/core/error.hpp"
#include "talus/core/slice_offsets.hpp"

#include <fmt/core.h>

#include <omp.h>

#include <algorithm>
#include <atomic>
#include <cmath>

namespace talus {

CellSort::CellSort(const Grid& grid, int reach_low, int reach_high, int block_cells)
    : reach_low_(reach_low), reach_high_(reach_high) {
  // Automatic: the smallest block (a multiple of the 4-node tile) that leaves each particle at
  // least one cell of drift between sorts. A requested size must leave that cell as well.
  block_cells_ = block_edge(reach_low, reach_high, 0);
  if (block_cells > 0) {
    if ((block_cells - reach_low - reach_high) / 2 < 1)
      throw input_error(fmt::format("colour blocks of {} cells leave no cell of slack for a support reaching {} + {} cells",
                                    block_cells, reach_low, reach_high));
    block_cells_ = block_cells;
  }
  slack_ = (block_cells_ - reach_low - reach_high) / 2;
  const auto& g = grid.geometry();
  for (int d = 0; d < 3; ++d) {
    cells_[d] = g.cells[d] + 2 * kPad;
    block_counts_[d] = (cells_[d] + block_cells_ - 1) / block_cells_;
    if (g.periodic[d]) {
      // Periodic axis: the blocks tile the domain's cells exactly, starting at its first cell, so
      // that the block after the last is block 0 again (the scene checks the count, cell_sort.hpp).
      block_shift_[d] = kPad;
      block_counts_[d] = g.cells[d] / block_cells_;
      if (!periodic_blocks_fit(g.cells[d], block_cells_))
        throw input_error(fmt::format("{} cells along periodic axis {} do not make 1 or an even number of colour blocks of {} cells",
                                      g.cells[d], "xyz"[d], block_cells_));
    }
  }
  bbox_block_index_.assign(static_cast<std::size_t>(block_counts_[0]) * block_counts_[1] * block_counts_[2], 0);
  tile_flag_.assign(grid.tile_count(), 0);
}

std::array<int, 3> CellSort::block_origin(std::size_t b) const {
  const std::uint32_t index = blocks_[b];
  const int bz = static_cast<int>(index % block_counts_[2]);
  const int by = static_cast<int>((index / block_counts_[2]) % block_counts_[1]);
  const int bx = static_cast<int>(index / (static_cast<std::uint32_t>(block_counts_[2]) * block_counts_[1]));
  return {bx * block_cells_ + block_shift_[0], by * block_cells_ + block_shift_[1], bz * block_cells_ + block_shift_[2]};
}

int CellSort::block_edge(int reach_low, int reach_high, int requested) {
  if (requested > 0) return requested;
  int edge = kTileEdge;
  while ((edge - reach_low - reach_high) / 2 < 1) edge += kTileEdge;
  return edge;
}

void CellSort::sort(ParticleStore& particles, Grid& grid) {
  own_scratch_.reserve(particles.size());
  sort(particles, grid, own_scratch_);
}

void CellSort::sort(ParticleStore& particles, Grid& grid, ParticleScratch& scratch) {
  const std::size_t n = particles.size();
  const auto& g = grid.geometry();
  const int bc = block_cells_;
  const int cells_per_block = bc * bc * bc;
  // The scratch's planes: each particle's block (0) and local cell (1), the particles in block
  // order (2), in (block, cell) order (3); the permutation's buffer (4-5).
  scratch.reserve(n);
  const std::span<std::uint32_t> particle_block = scratch.plane<std::uint32_t>(0, n);
  const std::span<std::uint32_t> particle_cell = scratch.plane<std::uint32_t>(1, n);
  const std::span<std::uint32_t> by_block = scratch.plane<std::uint32_t>(2, n);
  const std::span<std::uint32_t> order = scratch.plane<std::uint32_t>(3, n);

  // 1. Block and local cell of every particle (parallel: independent per particle).
  //    On a terrain grid the third coordinate is w = z - z_b(x), the map of the transfer kernels.
  long long outside = -1;
  const bool terrain = grid.has_terrain();
  const ProfileTerrain& bed = grid.profile_terrain();
#pragma omp parallel for schedule(static) reduction(max : outside)
  for (std::size_t p = 0; p < n; ++p) {
    int c[3];
    bool inside = true;
    const double position[3] = {particles.x[0][p], particles.x[1][p],
                                terrain ? particles.x[2][p] - bed.height(particles.x[0][p]) : particles.x[2][p]};
    for (int d = 0; d < 3; ++d) {
      const double xi = g.to_grid(d, position[d]);
      c[d] = g.cell_of(d, position[d]) - block_shift_[d];  // cells counted from the blocks' first cell
      inside = inside && xi >= block_shift_[d] && c[d] < block_counts_[d] * bc && xi < cells_[d];
    }
    if (!inside) {
      outside = std::max(outside, static_cast<long long>(p));
      c[0] = c[1] = c[2] = 0;
    }
    const int b[3] = {c[0] / bc, c[1] / bc, c[2] / bc};
    particle_block[p] = static_cast<std::uint32_t>((static_cast<std::size_t>(b[0]) * block_counts_[1] + b[1]) * block_counts_[2] + b[2]);
    particle_cell[p] = static_cast<std::uint32_t>(((c[0] - b[0] * bc) * bc + (c[1] - b[1] * bc)) * bc + (c[2] - b[2] * bc));
  }
  if (outside >= 0) {
    const auto p = static_cast<std::size_t>(outside);
    throw instability_error(fmt::format("particle {} left the grid: position ({:.6g}, {:.6g}, {:.6g})",
                                        particles.id[p], particles.x[0][p], particles.x[1][p], particles.x[2][p]));
  }

  // 2.-3. The stable counting sort by key = (compact block, local cell), in parallel and with the
  //    order of a serial one (the results must not depend on the thread count):
  //    2. active blocks in ascending bounding-box order (flag, then a compaction over the box);
  //    3. a stable counting sort by block: each thread counts and places a contiguous slice of the
  //       particles, the slices' offsets within a block follow the slice order;
  //    4. within each block, a stable counting sort by local cell.
  //    Ties keep the particles' current order at every stage, as the serial counting sort did.
  const std::size_t box_blocks = bbox_block_index_.size();
  for (std::uint32_t b : blocks_) bbox_block_index_[b] = 0;  // clear only what the last sort set
  const int max_threads = omp_get_max_threads();
  slice_blocks_.assign(static_cast<std::size_t>(max_threads) + 1, 0);
#pragma omp parallel
  {
    const std::size_t threads = static_cast<std::size_t>(omp_get_num_threads());
    const std::size_t t = static_cast<std::size_t>(omp_get_thread_num());
#pragma omp for schedule(static)
    for (std::size_t p = 0; p < n; ++p) std::atomic_ref<std::uint32_t>(bbox_block_index_[particle_block[p]]).store(1, std::memory_order_relaxed);
    // (the implicit barrier: every flag is set) each thread compacts a contiguous part of the box
    const std::size_t box_begin = box_blocks * t / threads, box_end = box_blocks * (t + 1) / threads;
    std::uint32_t found = 0;
    for (std::size_t i = box_begin; i < box_end; ++i) found += bbox_block_index_[i] != 0;
    slice_blocks_[t + 1] = found;
#pragma omp barrier
#pragma omp single
    {
      for (std::size_t u = 0; u < threads; ++u) slice_blocks_[u + 1] += slice_blocks_[u];
      blocks_.resize(slice_blocks_[threads]);
    }
    std::uint32_t next = slice_blocks_[t];
    for (std::size_t i = box_begin; i < box_end; ++i)
      if (bbox_block_index_[i]) {
        blocks_[next] = static_cast<std::uint32_t>(i);
        bbox_block_index_[i] = next++;
      }
  }
  const std::size_t blocks = blocks_.size();
  const std::size_t keys = blocks * cells_per_block;
  cell_start_.resize(keys + 1);
  block_start_.resize(blocks + 1);
  int threads_used = 1;
#pragma omp parallel
  {
#pragma omp single
    {
      threads_used = omp_get_num_threads();
      slice_counts_.assign(static_cast<std::size_t>(threads_used) * blocks, 0);
    }
    const std::size_t threads = static_cast<std::size_t>(threads_used);
    const std::size_t t = static_cast<std::size_t>(omp_get_thread_num());
    const std::size_t begin = n * t / threads, end = n * (t + 1) / threads;
    std::uint32_t* counts = slice_counts_.data() + t * blocks;
    for (std::size_t p = begin; p < end; ++p) {
      const std::uint32_t b = bbox_block_index_[particle_block[p]];
      particle_block[p] = b;  // now the compact block
      ++counts[b];
    }
    // Each block's size, then (one thread) the blocks' offsets, then each slice's offset in each block.
    slice_offsets_in_region(slice_counts_.data(), threads, blocks, block_start_.data(), [] {});
    // (every slice's offsets are known) place the slice, block by block
    for (std::size_t p = begin; p < end; ++p) by_block[counts[particle_block[p]]++] = static_cast<std::uint32_t>(p);
#pragma omp barrier
    // 4. Within each block, by local cell (stable).
    std::vector<std::uint32_t> cell_count(static_cast<std::size_t>(cells_per_block) + 1);
#pragma omp for schedule(dynamic, 1)
    for (std::size_t b = 0; b < blocks; ++b) {
      std::fill(cell_count.begin(), cell_count.end(), 0);
      const std::uint32_t first = block_start_[b], last = block_start_[b + 1];
      for (std::uint32_t i = first; i < last; ++i) ++cell_count[particle_cell[by_block[i]] + 1];
      std::uint32_t* starts = cell_start_.data() + b * cells_per_block;
      std::uint32_t offset = first;
      for (int l = 0; l < cells_per_block; ++l) {
        starts[l] = offset;
        offset += cell_count[l + 1];
        cell_count[l + 1] = starts[l];  // now the running insert position of cell l
      }
      for (std::uint32_t i = first; i < last; ++i) {
        const std::uint32_t p = by_block[i];
        order[cell_count[particle_cell[p] + 1]++] = p;
      }
    }
  }
  cell_start_[keys] = static_cast<std::uint32_t>(n);
  particles.permute(order, scratch, 4);
  // The parallel regions of this sort (work recorder): the cell of each particle, the two above, one per permuted array.
  parallel_regions_ = 3;
  particles.for_each_integer_array([&](const char*, const auto& a) { parallel_regions_ += !a.empty(); });
  particles.for_each_double_array([&](const char*, const ParticleArray<double>& a) { parallel_regions_ += !a.empty(); });

  // What follows is serial bookkeeping over the blocks (timed for the work recorder).
  const double serial_start = omp_get_wtime();

  for (auto& c : colour_blocks_) c.clear();
  for (std::size_t b = 0; b < blocks_.size(); ++b) {
    const auto o = block_origin(b);
    const int colour = (((o[0] - block_shift_[0]) / bc) & 1) * 4 + (((o[1] - block_shift_[1]) / bc) & 1) * 2 +
                       (((o[2] - block_shift_[2]) / bc) & 1);
    colour_blocks_[colour].push_back(static_cast<std::uint32_t>(b));
  }
  order_blocks();
  activate_tiles(grid);
  serial_seconds_ = omp_get_wtime() - serial_start;
}

void CellSort::set_block_order(BlockOrder order) {
  block_order_ = order;
  if (!blocks_.empty()) order_blocks();
}

// The blocks of one colour write disjoint nodes, so the order in which a pass visits them changes
// no sum: every node still receives its contributions colour by colour, each block's particles in
// sort order. Handing out the heaviest blocks first (schedule(dynamic, 1) over a list sorted by
// decreasing particle count) is the longest-processing-time rule (Graham 1969): the pass ends with
// the small blocks, and its critical path is at most 4/3 of the best, against up to 2x in index
// order, where a heavy block handed out last keeps one thread busy while the others wait.
void CellSort::order_blocks() {
  auto count = [this](std::uint32_t b) { return block_start_[b + 1] - block_start_[b]; };
  auto heavier = [&](std::uint32_t a, std::uint32_t b) { return count(a) > count(b) || (count(a) == count(b) && a < b); };
  work_order_.resize(blocks_.size());
  for (std::size_t b = 0; b < blocks_.size(); ++b) work_order_[b] = static_cast<std::uint32_t>(b);
  if (block_order_ == BlockOrder::Index) {
    for (auto& c : colour_blocks_) std::sort(c.begin(), c.end());
    return;
  }
  for (auto& c : colour_blocks_) std::sort(c.begin(), c.end(), heavier);
  std::sort(work_order_.begin(), work_order_.end(), heavier);
}

void CellSort::activate_tiles(Grid& grid) {
  for (std::uint32_t t : grid.active_tiles()) tile_flag_[t] = 0;
  const auto tiles = grid.tiles();
  const GridGeometry& g = grid.geometry();
  const auto nodes = g.nodes();
  std::vector<std::uint32_t> active;
  std::array<std::vector<int>, 3> tile_range;  // the tile coordinates a block may write, per axis
  for (std::size_t b = 0; b < blocks_.size(); ++b) {
    const auto o = block_origin(b);
    for (int d = 0; d < 3; ++d) {
      const int first = o[d] - slack_ - reach_low_, last = o[d] + block_cells_ - 1 + slack_ + reach_high_;
      std::vector<int>& r = tile_range[d];
      r.clear();
      if (g.periodic[d]) {
        // the nodes past a periodic face are the wrapped ones (Grid::wrap_node)
        for (int node = first; node <= last; ++node) r.push_back(g.wrap_node(d, node) / kTileEdge);
        std::sort(r.begin(), r.end());
        r.erase(std::unique(r.begin(), r.end()), r.end());
      } else {
        for (int t = std::max(0, first) / kTileEdge; t <= std::min(nodes[d] - 1, last) / kTileEdge; ++t) r.push_back(t);
      }
    }
    for (int i : tile_range[0])
      for (int j : tile_range[1])
        for (int k : tile_range[2]) {
          const std::size_t t = (static_cast<std::size_t>(i) * tiles[1] + j) * tiles[2] + k;
          if (!tile_flag_[t]) {
            tile_flag_[t] = 1;
            active.push_back(static_cast<std::uint32_t>(t));
          }
        }
  }
  std::sort(active.begin(), active.end());
  grid.set_active_tiles(std::move(active));
}

}  // namespace talus
