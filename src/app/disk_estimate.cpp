#include "disk_estimate.hpp"

#include "talus/driver/run_outputs.hpp"
#include "talus/io/vtu_writer.hpp"
#include "talus/solver/memory_estimate.hpp"

#include <fmt/core.h>

namespace talus::app {

namespace fs = std::filesystem;

std::string DiskEstimate::summary(const fs::path& out_dir) const {
  // (one frame a step at most: with a frame_interval shorter than the step, the steps estimated at
  // the initial time step bound the count, an estimate, not a bound: end 1 s, frame_interval 1e-5 s
  // counted 100 001 frames, 215 GB, where the run wrote 227)
  const std::string count =
      frames_by_steps ? fmt::format("about {} frames (one a step: ~{:.0f} steps at the initial time step, more if the "
                                    "flow speeds up)",
                                    frames, steps)
                      : fmt::format("{} frames", frames);
  std::string text = fmt::format(
      "{} of at most {}{} and {}: {} {}", count, format_bytes(double(bytes_per_frame)),
      compressed ? " (LZ4 writes less)" : "",
      checkpoints_at_once == 1 ? fmt::format("a checkpoint of {}", format_bytes(double(checkpoint_bytes)))
                               : fmt::format("{} checkpoints of {} while one replaces the other", checkpoints_at_once,
                                             format_bytes(double(checkpoint_bytes))),
      frames_by_steps ? "about" : "at most", format_bytes(total()));
  text += available ? fmt::format("; {} free in {}", format_bytes(double(*available)), out_dir.string())
                    : fmt::format("; free space in {} unknown", out_dir.string());
  return text;
}

std::optional<std::string> disk_warning(const DiskEstimate& disk, const fs::path& out_dir) {
  if (!disk.available || disk.total() <= double(*disk.available)) return std::nullopt;
  return fmt::format("the outputs may not fit: {} (a frame or checkpoint that cannot be written stops the run)",
                     disk.summary(out_dir));
}

DiskEstimate estimate_disk(const Scene& scene, std::size_t particles, const fs::path& out_dir) {
  DiskEstimate e;
  e.frames = frames_of_run(scene);
  e.steps = estimated_steps(scene);
  e.frames_by_steps = e.frames < frames_by_interval(scene);
  e.bytes_per_frame = particle_frame_bytes(particles, body_names(scene));
  e.compressed = scene.output.compress;
  e.checkpoint_bytes = particles * checkpoint_bytes_per_particle(scene);
  e.checkpoints_at_once = scene.output.checkpoint_interval > 0.0 ? 2 : 1;
  std::error_code ec;
  fs::path existing = fs::absolute(out_dir, ec);
  while (!existing.empty() && !fs::exists(existing, ec) && existing.has_relative_path()) existing = existing.parent_path();
  const fs::space_info space = fs::space(existing, ec);
  if (!ec) e.available = static_cast<std::size_t>(space.available);
  return e;
}

}  // namespace talus::app
