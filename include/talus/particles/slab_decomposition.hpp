#pragma once
// SlabDecomposition: which rank of a distributed run owns which particles (docs/architecture.md,
// "Distributed runs").
//
// The x axis (the flow direction of a flume) is cut into slabs of whole colour-block columns, one
// slab per rank; a particle belongs to the rank whose slab holds its cell. Slabs of whole columns
// keep every colour block on one rank, so the colouring inside a rank stays as in a serial run.
// The slab bounds are chosen from the work per column (particles) so that each rank gets an equal
// share, and moved again as the sand travels (rebalance, with hysteresis).
#include "talus/grid/grid.hpp"

#include <cstdint>
#include <span>
#include <vector>

namespace talus {

class SlabDecomposition {
 public:
  /// One rank owns every column.
  SlabDecomposition() = default;
  /// The padded cells along x (`work_per_cell`, one entry each: the seed points of a scene)
  /// grouped in block columns of `block_cells` cells (padded cell index 0 starts column 0), shared
  /// by `ranks` slabs of nearly equal work. Throws input_error when there are fewer columns than ranks.
  SlabDecomposition(int ranks, int block_cells, const std::vector<std::int64_t>& work_per_cell);

  int ranks() const { return static_cast<int>(first_column_.size()) - 1; }
  int columns() const { return columns_; }
  int block_cells() const { return block_cells_; }
  /// The rank owning padded cell i along x (cells before the first column: rank 0; past the last: the last rank).
  int owner_of_cell(int i) const;
  /// The block column of padded cell i, clamped to the grid.
  int column_of_cell(int i) const;
  /// First column of each rank's slab, and the end (ranks() + 1 values).
  const std::vector<int>& first_columns() const { return first_column_; }
  void set_first_columns(std::vector<int> first);

  /// The particles at x coordinates `x` per block column of `grid` (this rank's share: a run sums it
  /// over the ranks).
  std::vector<std::int64_t> particles_per_column(std::span<const double> x, const GridGeometry& grid) const;
  /// The work per cell of the constructor, summed per column.
  std::vector<std::int64_t> work_per_column(const std::vector<std::int64_t>& work_per_cell) const;

  /// The largest slab's work over the mean (1: perfect balance).
  double imbalance(const std::vector<std::int64_t>& work_per_column) const;
  /// Slab bounds that split `work_per_column` into `ranks` nearly equal parts, each slab at least
  /// one column wide: the greedy cut at each multiple of total/ranks.
  static std::vector<int> balanced_first_columns(const std::vector<std::int64_t>& work_per_column, int ranks);
  /// Rebalance when the imbalance exceeds `threshold` and the balanced cut improves it by more than
  /// half the excess (hysteresis: bounds do not flicker between two near-equal cuts). Returns
  /// whether the bounds moved.
  bool rebalance(const std::vector<std::int64_t>& work_per_column, double threshold);

 private:
  int block_cells_ = 4;
  int columns_ = 1;
  std::vector<int> first_column_{0, 1};
};

}  // namespace talus
