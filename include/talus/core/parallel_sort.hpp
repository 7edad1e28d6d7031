#pragma once
// A sort that uses the OpenMP threads and gives std::sort's result for any thread count, provided
// `less` is a strict total order on the values present (no two different elements compare equal:
// a tie-break on a unique id, say). Then the sorted sequence is unique, however it is reached.
//
// Why: the run loop's diagnostics sort every particle (the runout's quantiles in (s, id) order).
// Serial, that sort was a step's worth of work at each history row of a small scene and grows as
// n log n on large ones; in the scaling model (docs/performance.md, "Scaling") serial work is what
// limits the default flume at 16 threads.
//
// How: the range is cut into a power-of-two number of chunks, one a thread, each sorted with
// std::sort; then the chunks are merged pairwise, level by level, the merges of a level in parallel.
#include <omp.h>

#include <algorithm>
#include <cstddef>
#include <vector>

namespace talus {

/// Below this many elements a chunk is not worth a thread.
inline constexpr std::size_t kParallelSortMinChunk = 4096;

template <class T, class Less>
void parallel_sort(std::vector<T>& values, Less less) {
  const std::size_t n = values.size();
  int chunks = 1;
  const int threads = omp_in_parallel() ? 1 : omp_get_max_threads();
  while (2 * chunks <= threads && static_cast<std::size_t>(2 * chunks) * kParallelSortMinChunk <= n) chunks *= 2;
  if (chunks == 1) {
    std::sort(values.begin(), values.end(), less);
    return;
  }
  std::vector<std::size_t> bound(static_cast<std::size_t>(chunks) + 1);
  for (int i = 0; i <= chunks; ++i) bound[i] = n * static_cast<std::size_t>(i) / static_cast<std::size_t>(chunks);
  const auto at = [&](int i) { return values.begin() + static_cast<std::ptrdiff_t>(bound[i]); };
#pragma omp parallel for schedule(static, 1) num_threads(chunks)
  for (int i = 0; i < chunks; ++i) std::sort(at(i), at(i + 1), less);
  for (int width = 1; width < chunks; width *= 2) {
    const int merges = chunks / (2 * width);
#pragma omp parallel for schedule(static, 1) num_threads(merges)
    for (int m = 0; m < merges; ++m) {
      const int first = 2 * width * m;
      std::inplace_merge(at(first), at(first + width), at(first + 2 * width), less);
    }
  }
}

}  // namespace talus
