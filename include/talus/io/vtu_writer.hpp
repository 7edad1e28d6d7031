#pragma once
// Particle frames as VTK XML unstructured grids (.vtu, appended raw binary, optional LZ4), the
// .pvtu summary that makes ParaView open the pieces of a distributed run's frame as one data set,
// and the .pvd collection that makes it open the frames as one time series.
#include "talus/particles/particle_store.hpp"
#include "talus/scene/scene.hpp"

#include <optional>
#include <string>
#include <vector>

#include <vtkSmartPointer.h>

class vtkUnstructuredGrid;

namespace talus {

/// The component of a frame's 6-component array (stress, strain) that holds the solver's Voigt
/// component `voigt` (xx, yy, zz, yz, xz, xy: core/voigt.hpp). Frames use VTK's order of a
/// symmetric tensor, xx, yy, zz, xy, yz, xz (vtkMath::TensorFromSymmetricTensor), so that
/// ParaView's tensor filters (principal values, glyphs) pair the shear components rightly.
constexpr int vtk_symmetric_component(int voigt) {
  constexpr int kVtkOf[6] = {0, 1, 2, 4, 5, 3};
  return kVtkOf[voigt];
}

/// Whether a frame on disk (.vtu or .pvtu) holds its stress in VTK's order: its header names the
/// components (xx ... xz). Frames of builds before 2026-12-04 held the solver's Voigt order, unnamed:
/// false. nullopt when the file cannot be read or has no stress array.
std::optional<bool> frame_stress_in_vtk_order(const std::string& path);

/// The scene's body names in index order: a frame's `body_names` (the `body` point array holds
/// indices into it).
std::vector<std::string> body_names(const Scene& scene);

/// Write the particles to `path` (written to a temporary name, then renamed, so a reader never sees
/// a half-written frame). Point arrays: id, velocity, speed, stress (6 components in VTK's order
/// xx yy zz xy yz xz, named so), strain (6, likewise), density, volume, body. A store with no
/// particles (an empty rank of a distributed run) gives a valid file with 0 points and the same
/// arrays. With `time`, the file's field data holds
/// it as `TimeValue` (the array ParaView reads): a frame opened on its own, without the .pvd, has
/// its simulated time. With `body_names` (body_names(scene)), the field data holds them as the
/// string array `body_names`, name i for body index i: ParaView's spreadsheet view shows it
/// (attribute "Field Data"), so the `body` indices can be read as names.
void write_particles_vtu(const std::string& path, const ParticleStore& particles, bool compress,
                         std::optional<double> time = std::nullopt, const std::vector<std::string>& body_names = {});

/// The bytes write_particles_vtu writes for a frame of `particles` particles without compression
/// (the arrays' values, the vertex cells, their block headers and the XML around them), from the
/// arrays it builds, with its time and these body names; with compression (output.compress, the
/// default) a frame is smaller. For the disk-use estimate of `talus check` and `talus run`.
std::size_t particle_frame_bytes(std::size_t particles, const std::vector<std::string>& body_names = {});

/// One frame's point arrays (those write_particles_vtu writes), copied out of the store, in
/// parallel, when it is built: the store may change afterwards while the frame is written, on
/// another thread (FrameSeries). write(path, compress) gives the bytes write_particles_vtu would
/// have written at construction.
class ParticleFrame {
 public:
  explicit ParticleFrame(const ParticleStore& particles, std::optional<double> time = std::nullopt,
                         const std::vector<std::string>& body_names = {});
  ~ParticleFrame();
  /// As write_particles_vtu: through a temporary name and a rename.
  void write(const std::string& path, bool compress) const;

 private:
  vtkSmartPointer<vtkUnstructuredGrid> grid_;
};

/// Write (atomically) the .pvtu summary of one frame written in pieces: a PUnstructuredGrid
/// (GhostLevel 0) that declares the point arrays and point type write_particles_vtu writes for a
/// store with the arrays of `layout` (its particles are not read; it may hold none), and lists
/// `piece_files`, paths relative to the folder of `path`, in the order given.
void write_particles_pvtu(const std::string& path, const std::vector<std::string>& piece_files,
                          const ParticleStore& layout);

/// The .pvd index of a frame series; rewritten atomically after every frame. In a distributed run
/// every rank keeps the entries but only one writes the file: the others pass `writes_file` false.
class PvdIndex {
 public:
  explicit PvdIndex(std::string path, bool writes_file = true) : path_(std::move(path)), writes_file_(writes_file) {}
  void add(double time, const std::string& relative_file);
  /// Replace all entries (a restart: the frames written before the checkpoint) and rewrite.
  void assign(std::vector<std::pair<double, std::string>> entries);
  const std::string& path() const { return path_; }
  std::size_t size() const { return entries_.size(); }
  bool writes_file() const { return writes_file_; }

 private:
  void write() const;
  std::string path_;
  bool writes_file_;
  std::vector<std::pair<double, std::string>> entries_;
};

/// Write a VTK unstructured grid to `path` as .vtu (appended raw binary, LZ4 when `compress`)
/// through a temporary file and a rename; `what` names the file in the error ("particle frame").
void write_vtu_atomically(vtkUnstructuredGrid* grid, const std::string& path, bool compress, const char* what);

}  // namespace talus
