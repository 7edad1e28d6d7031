#pragma once
// What a run's frames may take on disk, against what the output folder's file system has free:
// `talus check` prints it, and `talus run` warns before it starts when the frames may not fit (a
// run that fills the disk stops at the frame that fails, exit code 2).
#include "talus/scene/scene.hpp"

#include <cstddef>
#include <filesystem>
#include <optional>
#include <string>

namespace talus::app {

struct DiskEstimate {
  std::size_t frames = 0;           // the most a run writes (driver/run_outputs.hpp frames_of_run)
  std::size_t bytes_per_frame = 0;  // uncompressed (io/vtu_writer.hpp): an upper bound with LZ4
  bool compressed = true;           // output.compress
  std::optional<std::size_t> available;  // free to this user on the output folder's file system
  double total() const { return double(frames) * double(bytes_per_frame); }  // (in double: 10^15 frames of 1 MB overflow 64 bits)
  /// "51 frames of at most 1.5 MB (LZ4 writes less): at most 76.5 MB; 20.1 GB free in runs/x".
  std::string summary(const std::filesystem::path& out_dir) const;
};

/// The estimate for a run of `scene` with `particles` particles into `out_dir` (which may not exist
/// yet: the free space is that of its nearest existing ancestor).
DiskEstimate estimate_disk(const Scene& scene, std::size_t particles, const std::filesystem::path& out_dir);

}  // namespace talus::app
