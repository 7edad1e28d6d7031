#pragma once
// BlockBuffers: the scatter without colour passes (solver.scatter = "block_buffers").
//
// The default scatter runs 8 colour passes with a barrier after each, so that two blocks that share
// nodes never run at once. A small scene has few blocks per colour (the default flume: 13 on
// average, 4 at the least), so on many threads most of them wait in every pass
// (docs/performance.md, "Scaling"). Here every block scatters into node records of its own — a box
// of edge() nodes per axis around the block, its cells widened by the slack and the shape's reach —
// all blocks in one parallel pass, and add_sum_stage() then adds the boxes into the grid's records,
// tile by tile in parallel, each node's boxes in ascending block order. Every node's sum is
// therefore the same for any thread count; it differs at round-off from the colour passes', which
// add particle by particle across blocks (the particle sums of each block are formed first here).
//
// Only the nodes a box's scatter reached are summed and, at the next scatter, cleared
// (open_box/close_box): a block's particles reach about 5^3 of the 7^3 nodes of a linear box.
//
// Memory: blocks x edge()^3 x 64 bytes (the default flume: 145 blocks of 7^3 nodes, 3.2 MB; the
// 1 M-particle B-spline shear bench with 8-cell blocks: 343 blocks of 16^3 nodes, 90 MB), kept between
// sorts. Periodic axes are not supported (their stencils wrap around the box).
#include "talus/grid/grid.hpp"
#include "talus/grid/tile_stages.hpp"
#include "talus/particles/cell_sort.hpp"

#include <array>
#include <cstddef>
#include <cstdint>
#include <memory>
#include <new>
#include <vector>

namespace talus {

class BlockBuffers {
 public:
  /// Size the boxes for the sort's blocks and list, per active tile of the grid, the boxes that
  /// overlap it (ascending block order). After every sort, before the next scatter.
  void prepare(const CellSort& sort, const Grid& grid);
  /// The serial part of the last prepare() in seconds (the pairs of boxes and tiles, their order
  /// and the prefix sum); the rest is kPrepareParallelRegions parallel loops (the work recorder).
  double last_serial_seconds() const { return serial_seconds_; }
  static constexpr int kPrepareParallelRegions = 3;

  /// Nodes per box edge: block_cells + 2 slack + the shape's reach below and above.
  int edge() const { return edge_; }
  /// The first node (padded indices) of block b's box.
  std::array<int, 3> first_node(std::size_t b) const {
    const auto o = block_origin_[b];
    return {o[0] - below_, o[1] - below_, o[2] - below_};
  }
  /// Block b's node records (edge()^3 of kNodeRecord doubles; node (i, j, k) of the box at
  /// ((i * edge + j) * edge + k) * kNodeRecord), zero, for a scatter into them: clears the nodes the
  /// last scatter into the box wrote (the whole box after a prepare()).
  double* open_box(std::size_t b);
  /// After the scatter into box b: the box-local nodes it wrote, [lo, hi) per axis (empty when
  /// lo >= hi). The sum adds only those, and the next open_box clears only those.
  void close_box(std::size_t b, const std::array<int, 3>& lo, const std::array<int, 3>& hi) {
    written_[b] = {lo[0], lo[1], lo[2], hi[0], hi[1], hi[2]};
  }
  /// The stage that adds the boxes' `fields` into the grid's node records (which the caller cleared
  /// or holds partial sums in), tile by tile: over the active tiles (an OwnTile stage, which the
  /// grid update can follow on the same tile) when covers_active_tiles(), else a loop of its own over
  /// the boxes' tiles. With `clear_first` each tile is zeroed (Grid::clear_tile) just before its
  /// sums, in the same loop: the step's grid clear without a pass and a parallel region of its
  /// own. Only when covers_active_tiles(). The stage reads the boxes when it runs (after the scatter).
  void add_sum_stage(TileStages& stages, Grid& grid, ScatteredFields fields, bool clear_first = false) const;
  /// Whether the tiles the boxes overlap are exactly the grid's active tiles at the last prepare()
  /// (both follow from the blocks' extent, so they are unless the grid changed since): then
  /// add_sum_stage(..., true) clears every active tile.
  bool covers_active_tiles() const { return covers_active_tiles_; }

  /// The bytes prepare() would hold for `blocks` blocks of `edge` nodes (the memory estimate).
  static std::size_t bytes_for(std::size_t blocks, int edge) {
    return blocks * static_cast<std::size_t>(edge) * edge * edge * kNodeRecord * sizeof(double);
  }

 private:
  /// `nodes` neighbouring node records of one box (from its node `from`, counted over all boxes)
  /// added to as many neighbouring records of the grid (from node `to`): along k the nodes of a
  /// tile are neighbours in both layouts (Grid::z_part), so a box's share of a tile is rows of runs.
  struct Run {
    std::uint64_t to;
    std::uint64_t from;
    std::uint32_t block;
    std::uint16_t nodes;
    std::int16_t i, j, k;  // box-local node of the run's first record
  };
  const double* records(std::size_t b) const { return data_.get() + b * box_doubles_; }
  /// add_sum_stage's stage for one set of fields.
  template <bool kMass, bool kMomentum, bool kForce>
  TileStages::Stage tile_sum(Grid& grid, bool clear_first) const;
  int edge_ = 0, below_ = 0;
  std::size_t box_doubles_ = 0;
  std::vector<std::array<int, 3>> block_origin_;  // first cell of each block
  std::vector<std::array<int, 6>> written_;       // per box: the nodes its last scatter wrote, lo and hi
  std::vector<std::uint8_t> stale_;               // per box: holds another block's sums (cleared whole)
  // The boxes, 64-byte aligned like the grid's records (the scatter loads and stores records as vectors).
  struct AlignedDelete {
    void operator()(double* p) const { ::operator delete[](p, std::align_val_t(64)); }
  };
  std::unique_ptr<double[], AlignedDelete> data_;
  std::size_t capacity_ = 0;  // doubles held (grown, never shrunk)
  std::vector<Run> runs_;                   // by tile, then block ascending
  std::vector<std::uint32_t> tile_starts_;  // per tile that boxes overlap: its first run (+1 end)
  std::vector<std::uint32_t> tiles_;        // the tiles that boxes overlap, ascending (one per tile_starts_ entry)
  std::vector<std::uint32_t> tile_counts_;  // prepare(): per thread and active tile, its pairs, then its next slot
  bool covers_active_tiles_ = false;
  double serial_seconds_ = 0.0;
};

}  // namespace talus
