#include "talus/particles/slab_decomposition.hpp"

#include "talus/core/error.hpp"

#include <fmt/core.h>

#include <algorithm>
#include <cmath>

namespace talus {

SlabDecomposition::SlabDecomposition(int ranks, int block_cells, const std::vector<std::int64_t>& work_per_cell)
    : block_cells_(block_cells),
      columns_(static_cast<int>((work_per_cell.size() + static_cast<std::size_t>(block_cells) - 1) / block_cells)) {
  if (ranks > columns_)
    throw input_error(fmt::format("{} ranks need at least {} colour-block columns along x, one a rank; the grid's {} cells "
                                  "along x, ghost cells included, make {} columns of {} cells: use at most {} rank{} or "
                                  "more cells along x",
                                  ranks, ranks, work_per_cell.size(), columns_, block_cells, columns_, columns_ == 1 ? "" : "s"));
  first_column_ = balanced_first_columns(work_per_column(work_per_cell), ranks);
}

std::vector<std::int64_t> SlabDecomposition::work_per_column(const std::vector<std::int64_t>& work_per_cell) const {
  std::vector<std::int64_t> work(columns_, 0);
  for (std::size_t i = 0; i < work_per_cell.size(); ++i) work[column_of_cell(static_cast<int>(i))] += work_per_cell[i];
  return work;
}

std::vector<std::int64_t> SlabDecomposition::particles_per_column(std::span<const double> x,
                                                                  const GridGeometry& grid) const {
  std::vector<std::int64_t> work(columns_, 0);
  for (double xp : x) ++work[column_of_cell(grid.cell_of(0, xp))];
  return work;
}

int SlabDecomposition::column_of_cell(int i) const { return std::clamp(i / block_cells_, 0, columns_ - 1); }

int SlabDecomposition::owner_of_cell(int i) const {
  const int c = column_of_cell(i);
  // the last slab whose first column is <= c
  return static_cast<int>(std::upper_bound(first_column_.begin() + 1, first_column_.end() - 1, c) - first_column_.begin()) - 1;
}

void SlabDecomposition::set_first_columns(std::vector<int> first) { first_column_ = std::move(first); }

double SlabDecomposition::imbalance(const std::vector<std::int64_t>& work) const {
  std::int64_t total = 0, largest = 0;
  for (int r = 0; r < ranks(); ++r) {
    std::int64_t w = 0;
    for (int c = first_column_[r]; c < first_column_[r + 1]; ++c) w += work[c];
    total += w;
    largest = std::max(largest, w);
  }
  return total > 0 ? static_cast<double>(largest) * ranks() / static_cast<double>(total) : 1.0;
}

std::vector<int> SlabDecomposition::balanced_first_columns(const std::vector<std::int64_t>& work, int ranks) {
  const int columns = static_cast<int>(work.size());
  std::int64_t total = 0;
  for (std::int64_t w : work) total += w;
  std::vector<int> first(ranks + 1, 0);
  first[ranks] = columns;
  std::int64_t cumulative = 0;
  int c = 0;
  for (int r = 1; r < ranks; ++r) {
    // the cut whose work before it is nearest r/ranks of the total; every slab keeps at least one column
    const double target = static_cast<double>(total) * r / ranks;
    auto distance = [&](std::int64_t before) { return std::abs(static_cast<double>(before) - target); };
    while (c < columns - (ranks - r) && (c <= first[r - 1] || distance(cumulative + work[c]) <= distance(cumulative))) {
      cumulative += work[c];
      ++c;
    }
    first[r] = c;
  }
  return first;
}

bool SlabDecomposition::rebalance(const std::vector<std::int64_t>& work, double threshold) {
  const double now = imbalance(work);
  if (now <= threshold) return false;
  SlabDecomposition balanced = *this;
  balanced.first_column_ = balanced_first_columns(work, ranks());
  const double after = balanced.imbalance(work);
  if (now - after <= 0.5 * (now - 1.0)) return false;
  first_column_ = std::move(balanced.first_column_);
  return true;
}

}  // namespace talus
