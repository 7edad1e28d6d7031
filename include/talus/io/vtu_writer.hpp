#pragma once
// Particle frames as VTK XML unstructured grids (.vtu, appended raw binary, optional LZ4) and the
// .pvd collection that makes ParaView open the frames as one time series.
#include "talus/particles/particle_store.hpp"
#include "talus/scene/scene.hpp"

#include <string>
#include <vector>

class vtkUnstructuredGrid;

namespace talus {

/// Write the particles to `path` (written to a temporary name, then renamed, so a reader never sees
/// a half-written frame). Point arrays: id, velocity, speed, stress (6 components xx yy zz yz xz xy),
/// strain (6), density, volume, body.
void write_particles_vtu(const std::string& path, const ParticleStore& particles, bool compress);

/// The .pvd index of a frame series; rewritten atomically after every frame.
class PvdIndex {
 public:
  explicit PvdIndex(std::string path) : path_(std::move(path)) {}
  void add(double time, const std::string& relative_file);
  /// Replace all entries (a restart: the frames written before the checkpoint) and rewrite.
  void assign(std::vector<std::pair<double, std::string>> entries);
  const std::string& path() const { return path_; }
  std::size_t size() const { return entries_.size(); }

 private:
  void write() const;
  std::string path_;
  std::vector<std::pair<double, std::string>> entries_;
};

/// Write a VTK unstructured grid to `path` as .vtu (appended raw binary, LZ4 when `compress`)
/// through a temporary file and a rename; `what` names the file in the error ("particle frame").
void write_vtu_atomically(vtkUnstructuredGrid* grid, const std::string& path, bool compress, const char* what);

/// Write `text` to `path` through a temporary file and a rename (atomic on POSIX file systems).
void write_file_atomically(const std::string& path, const std::string& text);

}  // namespace talus
