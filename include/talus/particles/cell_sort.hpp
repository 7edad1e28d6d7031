#pragma once
// Sorting particles by cell, and the colour blocks that make the scatter race-free.
//
// Cells are grouped into cubic colour blocks of `block_cells`^3 cells; a block's colour is the parity
// of its block coordinates (8 colours). Particles are sorted (stable counting sort, O(N)) by
// (block, cell within block), so each block's particles are contiguous and ordered by cell.
// A block of particles writes the nodes of its cells widened by the shape function's reach; two
// blocks of one colour are one block apart, so with
//     2 * slack + reach_low + reach_high <= block_cells
// their writes never meet even after every particle has moved `slack` cells since the sort.
// Each colour is then one parallel loop over blocks with no atomics, and every node receives its
// contributions in the same order for any thread count: results are bit-identical.
//
// Periodic axes (GridGeometry::periodic): the blocks start at the domain's first cell and tile its
// cells exactly, and stencils wrap (Grid::wrap_node), so the block after the last one is the first
// one. The parity colouring stays race-free around the ring when the axis holds 1 block (it only
// meets itself) or an even number of blocks (neighbours around the seam differ in parity):
// periodic_blocks_fit; the scene refuses other cell counts.
//
// Work and memory scale with the occupied blocks: the only arrays over the bounding box are one
// counter per block and one flag per 4^3 node tile.
#include "talus/grid/grid.hpp"
#include "talus/particles/particle_scratch.hpp"
#include "talus/particles/particle_store.hpp"

#include <array>
#include <cstdint>
#include <vector>

namespace talus {

/// The order in which a pass over blocks hands them out (the results do not depend on it).
enum class BlockOrder {
  LargestFirst,  // by decreasing particle count: load balance by work (the default)
  Index,         // by block index (bounding-box order; talus before the scaling model)
};

class CellSort {
 public:
  CellSort() = default;
  /// reach_low/high: the shape function's support in cells around the particle's cell;
  /// block_cells: the block edge (0: automatic, the smallest multiple of 4 with one cell of slack).
  CellSort(const Grid& grid, int reach_low, int reach_high, int block_cells = 0);

  /// Sort the store by (block, cell), rebuild offsets and colour lists, and activate the grid tiles
  /// the blocks may write until the next sort. The per-particle keys and orders, and the buffer of
  /// the permutation, live in `scratch` (all 6 planes; its contents before and after mean nothing).
  void sort(ParticleStore& particles, Grid& grid, ParticleScratch& scratch);
  /// The same with a scratch of the sort's own (kept between sorts): tests and tools.
  void sort(ParticleStore& particles, Grid& grid);

  /// The block edge the constructor picks for a support (requested > 0: that one).
  static int block_edge(int reach_low, int reach_high, int requested);
  /// Whether `cells` along a periodic axis make 1 block or an even number of blocks of `block_cells`.
  static bool periodic_blocks_fit(int cells, int block_cells) {
    return cells % block_cells == 0 && (cells == block_cells || (cells / block_cells) % 2 == 0);
  }

  int block_cells() const { return block_cells_; }
  int slack() const { return slack_; }
  /// The shape's support in cells below and above a particle's cell (the constructor's).
  int reach_low() const { return reach_low_; }
  int reach_high() const { return reach_high_; }
  std::size_t block_count() const { return blocks_.size(); }
  /// Cell coordinates of the first cell of active block b.
  std::array<int, 3> block_origin(std::size_t b) const;
  std::uint32_t block_begin(std::size_t b) const { return block_start_[b]; }
  std::uint32_t block_end(std::size_t b) const { return block_start_[b + 1]; }
  /// The blocks of colour c, in hand-out order (block_order()).
  const std::vector<std::uint32_t>& colour(int c) const { return colour_blocks_[c]; }
  /// All blocks in hand-out order, for passes over every block (the stress pass).
  const std::vector<std::uint32_t>& blocks_in_work_order() const { return work_order_; }
  BlockOrder block_order() const { return block_order_; }
  /// Reorder the hand-out lists (takes effect at once and at every later sort).
  void set_block_order(BlockOrder order);
  /// Particles of cell (local index l in block b): [cell_start[b*cells_per_block + l], ... + 1).
  const std::vector<std::uint32_t>& cell_start() const { return cell_start_; }
  /// The padded cell where the blocks start along each axis: block (bi, bj, bk) holds the cells
  /// block_shift + b * block_cells ... + block_cells - 1 (0, or kPad along a periodic axis).
  const std::array<int, 3>& block_shift() const { return block_shift_; }
  /// Compact index of active block (bi, bj, bk) (block coordinates from block_shift()), or -1 when
  /// the block is outside the bounding box or no particle was sorted into it. Inline: the MLS
  /// search asks for every column of cells it walks.
  long long active_block(int bi, int bj, int bk) const {
    if (bi < 0 || bj < 0 || bk < 0 || bi >= block_counts_[0] || bj >= block_counts_[1] || bk >= block_counts_[2])
      return -1;
    const std::uint32_t index =
        static_cast<std::uint32_t>((static_cast<std::size_t>(bi) * block_counts_[1] + bj) * block_counts_[2] + bk);
    // bbox_block_index_ holds the compact index for active blocks and 0 elsewhere; 0 is also block
    // 0's index, so confirm against blocks_.
    const std::uint32_t b = bbox_block_index_[index];
    return b < blocks_.size() && blocks_[b] == index ? static_cast<long long>(b) : -1;
  }

  /// The last sort's serial bookkeeping (colour lists, hand-out order, active tiles) in seconds, and
  /// its number of parallel regions: what the work recorder splits the sort into.
  double last_serial_seconds() const { return serial_seconds_; }
  int last_parallel_regions() const { return parallel_regions_; }

  /// Whether a particle sorted into the block whose origin is block_origin(b) may sit in cell (i, j, k)
  /// without breaking the colouring (the origin computed once for all the block's particles).
  bool within_slack_of(const std::array<int, 3>& o, int i, int j, int k) const {
    return i >= o[0] - slack_ && i < o[0] + block_cells_ + slack_ && j >= o[1] - slack_ &&
           j < o[1] + block_cells_ + slack_ && k >= o[2] - slack_ && k < o[2] + block_cells_ + slack_;
  }

 private:
  void activate_tiles(Grid& grid);
  void order_blocks();

  int block_cells_ = 4;
  int slack_ = 1;
  int reach_low_ = 0, reach_high_ = 1;
  std::array<int, 3> cells_{};         // cells per axis including ghosts
  std::array<int, 3> block_counts_{};  // blocks per axis over the bounding box
  std::array<int, 3> block_shift_{};   // padded cell of the first block's origin (kPad along periodic axes)
  std::vector<std::uint32_t> blocks_;       // bounding-box index of each active block, ascending
  std::vector<std::uint32_t> block_start_;  // particle offsets per active block (+1 end)
  std::vector<std::uint32_t> cell_start_;   // particle offsets per cell of active blocks (+1 end)
  std::array<std::vector<std::uint32_t>, 8> colour_blocks_;
  std::vector<std::uint32_t> work_order_;  // all blocks in hand-out order
  BlockOrder block_order_ = BlockOrder::LargestFirst;
  // Scratch reused between sorts.
  std::vector<std::uint32_t> bbox_block_index_;   // per bounding-box block: count, then compact index + 1
  ParticleScratch own_scratch_;              // only for sort(particles, grid)
  std::vector<std::uint32_t> slice_counts_;  // per thread slice and block: count, then insert position
  std::vector<std::uint32_t> slice_blocks_;  // active blocks per thread's part of the box, then offsets
  double serial_seconds_ = 0.0;
  int parallel_regions_ = 0;
  std::vector<std::uint8_t> tile_flag_;
};

}  // namespace talus
