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

/// Below this many elements a chunk is not worth a thread: a std::sort of 1024 elements takes tens
/// of µs, a parallel region a few. (4096 until 2026-12-05: the default flume's 15 584 particles then
/// sorted in 2 chunks on any number of threads, about 1 ms a history row on a thread of this VM.)
inline constexpr std::size_t kParallelSortMinChunk = 1024;

/// The chunks parallel_sort cuts n elements into on `threads` threads (a power of two).
inline int parallel_sort_chunks(std::size_t n, int threads) {
  int chunks = 1;
  while (2 * chunks <= threads && static_cast<std::size_t>(2 * chunks) * kParallelSortMinChunk <= n) chunks *= 2;
  return chunks;
}

/// The parallel regions parallel_sort opens for n elements on `threads` threads: one for the
/// chunks, one per level of merges (none when it sorts in one chunk).
inline int parallel_sort_regions(std::size_t n, int threads) {
  int regions = 0;
  for (int chunks = parallel_sort_chunks(n, threads); chunks > 1; chunks /= 2) ++regions;
  return regions > 0 ? regions + 1 : 0;
}

template <class T, class Less>
void parallel_sort(std::vector<T>& values, Less less) {
  const std::size_t n = values.size();
  const int chunks = parallel_sort_chunks(n, omp_in_parallel() ? 1 : omp_get_max_threads());
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
