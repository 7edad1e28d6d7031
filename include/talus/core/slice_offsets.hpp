#pragma once
// The middle step of a parallel counting sort, inside an open OpenMP region.
//
// Each of the team's `slices` threads has counted the items of its contiguous slice per bucket in
// counts[slice * buckets + bucket]. slice_offsets_in_region turns those counts into each slice's
// first slot in each bucket - the buckets in order and, within a bucket, the slices in order - so
// that each slice then writing its items in its own order gives the stable order for any thread
// count; it also sets bucket_start[0 .. buckets] (each bucket's first slot, then the total).
// Used by CellSort (particles by block) and BlockBuffers (pairs of boxes and tiles by tile).
#include <omp.h>

#include <cstddef>
#include <cstdint>

namespace talus {

/// Every thread of the team must call it (it holds worksharing loops and barriers), after its
/// counts are written; it returns when every slot is known. `on_prefix` runs on one thread once
/// bucket_start is complete (to size the output, say); `serial_seconds`, when given, receives the
/// time of that one-thread part (the prefix and on_prefix), for the work recorder.
template <class OnPrefix>
void slice_offsets_in_region(std::uint32_t* counts, std::size_t slices, std::size_t buckets, std::uint32_t* bucket_start,
                             OnPrefix&& on_prefix, double* serial_seconds = nullptr) {
#pragma omp barrier
#pragma omp for schedule(static)
  for (std::size_t b = 0; b < buckets; ++b) {
    std::uint32_t total = 0;
    for (std::size_t u = 0; u < slices; ++u) total += counts[u * buckets + b];
    bucket_start[b + 1] = total;
  }
#pragma omp single
  {
    const double start = omp_get_wtime();
    bucket_start[0] = 0;
    for (std::size_t b = 0; b < buckets; ++b) bucket_start[b + 1] += bucket_start[b];
    on_prefix();
    if (serial_seconds) *serial_seconds = omp_get_wtime() - start;
  }
#pragma omp for schedule(static)
  for (std::size_t b = 0; b < buckets; ++b) {
    std::uint32_t offset = bucket_start[b];
    for (std::size_t u = 0; u < slices; ++u) {
      const std::uint32_t c = counts[u * buckets + b];
      counts[u * buckets + b] = offset;
      offset += c;
    }
  }
}

}  // namespace talus
