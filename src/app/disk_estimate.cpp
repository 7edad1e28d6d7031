#include "disk_estimate.hpp"

#include "talus/driver/run_outputs.hpp"
#include "talus/io/vtu_writer.hpp"
#include "talus/solver/memory_estimate.hpp"

#include <fmt/core.h>

namespace talus::app {

namespace fs = std::filesystem;

std::string DiskEstimate::summary(const fs::path& out_dir) const {
  std::string text = fmt::format(
      "{} frames of at most {}{} and {}: at most {}", frames, format_bytes(double(bytes_per_frame)),
      compressed ? " (LZ4 writes less)" : "",
      checkpoints_at_once == 1 ? fmt::format("a checkpoint of {}", format_bytes(double(checkpoint_bytes)))
                               : fmt::format("{} checkpoints of {} while one replaces the other", checkpoints_at_once,
                                             format_bytes(double(checkpoint_bytes))),
      format_bytes(total()));
  text += available ? fmt::format("; {} free in {}", format_bytes(double(*available)), out_dir.string())
                    : fmt::format("; free space in {} unknown", out_dir.string());
  return text;
}

DiskEstimate estimate_disk(const Scene& scene, std::size_t particles, const fs::path& out_dir) {
  DiskEstimate e;
  e.frames = frames_of_run(scene);
  e.bytes_per_frame = particle_frame_bytes(particles);
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
