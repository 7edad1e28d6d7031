#pragma once
// What a run's frames and checkpoint may take on disk, against what the output folder's file system has free:
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
  /// The frames are bounded by the steps, one a step, at the steps estimated at the initial time step
  /// (output.frame_interval shorter than the step): then an estimate, short of a flow that speeds up.
  bool frames_by_steps = false;
  double steps = 0.0;               // driver/run_outputs.hpp estimated_steps
  std::size_t bytes_per_frame = 0;  // uncompressed (io/vtu_writer.hpp): an upper bound with LZ4
  bool compressed = true;           // output.compress
  /// checkpoint.h5: written by every run that is stopped (signal, --stop-after, an instability) and
  /// every output.checkpoint_interval, through a temporary file, so that two are on disk while a
  /// periodic one is replaced
  std::size_t checkpoint_bytes = 0;
  int checkpoints_at_once = 1;
  std::optional<std::size_t> available;  // free to this user on the output folder's file system
  // (in double: 10^15 frames of 1 MB overflow 64 bits)
  double total() const {
    return double(frames) * double(bytes_per_frame) + double(checkpoints_at_once) * double(checkpoint_bytes);
  }
  /// "51 frames of at most 1.5 MB (LZ4 writes less) and a checkpoint of 1.6 MB: at most 78.0 MB;
  /// 20.1 GB free in runs/x".
  std::string summary(const std::filesystem::path& out_dir) const;
};

/// "the outputs may not fit: ..." where the estimate exceeds the free space (`talus check` and
/// `talus run` print it as a warning before the run); none where it fits or the space is unknown.
std::optional<std::string> disk_warning(const DiskEstimate& disk, const std::filesystem::path& out_dir);

/// The estimate for a run of `scene` with `particles` particles into `out_dir` (which may not exist
/// yet: the free space is that of its nearest existing ancestor).
DiskEstimate estimate_disk(const Scene& scene, std::size_t particles, const std::filesystem::path& out_dir);

}  // namespace talus::app
