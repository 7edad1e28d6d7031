#include "talus/io/vtu_writer.hpp"

#include "talus/core/error.hpp"
#include "talus/io/atomic_file.hpp"

#include <fmt/core.h>
#include <vtkCellArray.h>
#include <vtkCellType.h>
#include <vtkDoubleArray.h>
#include <vtkErrorCode.h>
#include <vtkFieldData.h>
#include <vtkNew.h>
#include <vtkObject.h>
#include <vtkPointData.h>
#include <vtkPoints.h>
#include <vtkSmartPointer.h>
#include <vtkStringArray.h>
#include <vtkType.h>
#include <vtkTypeInt32Array.h>
#include <vtkTypeInt64Array.h>
#include <vtkUnsignedShortArray.h>
#include <vtkUnstructuredGrid.h>
#include <vtkXMLUnstructuredGridWriter.h>

#include <bit>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <stdexcept>

namespace talus {

namespace {

vtkNew<vtkDoubleArray> make_array(const char* name, int components, vtkIdType n) {
  vtkNew<vtkDoubleArray> a;
  a->SetName(name);
  a->SetNumberOfComponents(components);
  a->SetNumberOfTuples(n);
  return a;
}

// VTK's order of a symmetric tensor (vtk_symmetric_component): the names say it too.
void name_symmetric_components(vtkDoubleArray* a) {
  const char* names[6] = {"xx", "yy", "zz", "xy", "yz", "xz"};
  for (int c = 0; c < 6; ++c) a->SetComponentName(c, names[c]);
}

/// The grid write_particles_vtu writes: one vertex cell and one tuple of each point array per
/// particle. With `with_particles` false the same arrays are built with no tuples: the layout the
/// .pvtu summary declares. Both writers build their arrays here, so the two cannot disagree.
vtkSmartPointer<vtkUnstructuredGrid> particle_grid(const ParticleStore& P, bool with_particles) {
  const auto n = with_particles ? static_cast<vtkIdType>(P.size()) : vtkIdType{0};
  vtkNew<vtkPoints> points;
  points->SetDataTypeToDouble();
  points->SetNumberOfPoints(n);
  auto velocity = make_array("velocity", 3, n);
  auto speed = make_array("speed", 1, n);
  auto stress = make_array("stress", 6, n);
  auto strain = make_array("strain", 6, n);
  auto density = make_array("density", 1, n);
  auto volume = make_array("volume", 1, n);
  name_symmetric_components(stress);
  name_symmetric_components(strain);
  vtkNew<vtkTypeInt64Array> id;
  id->SetName("id");
  id->SetNumberOfTuples(n);
  vtkNew<vtkUnsignedShortArray> body;
  body->SetName("body");
  body->SetNumberOfTuples(n);
  vtkNew<vtkTypeInt32Array> offsets, connectivity;
  offsets->SetNumberOfTuples(n + 1);
  connectivity->SetNumberOfTuples(n);

  // Filled through raw pointers, in parallel: a frame of the h = 0.005 m flume (244 k particles)
  // took about 90 ms on one core, this copy a fifth of it (the rest is VTK's LZ4 and the write).
  // Each particle writes only its own tuples, so the bytes are the same for any thread count.
  double* const xyz = vtkDoubleArray::SafeDownCast(points->GetData())->GetPointer(0);
  double* const vel = velocity->GetPointer(0);
  double* const spd = speed->GetPointer(0);
  double* const sig = stress->GetPointer(0);
  double* const eps = strain->GetPointer(0);
  double* const rho = density->GetPointer(0);
  double* const vol = volume->GetPointer(0);
  auto* const ids = id->GetPointer(0);
  unsigned short* const bodies = body->GetPointer(0);
  auto* const offset = offsets->GetPointer(0);
  auto* const vertex = connectivity->GetPointer(0);
#pragma omp parallel for schedule(static)
  for (vtkIdType p = 0; p < n; ++p) {
    double v2 = 0.0;
    for (int d = 0; d < 3; ++d) {
      xyz[3 * p + d] = P.x[d][p];
      vel[3 * p + d] = P.v[d][p];
      v2 += P.v[d][p] * P.v[d][p];
    }
    spd[p] = std::sqrt(v2);
    for (int c = 0; c < 6; ++c) {
      sig[6 * p + vtk_symmetric_component(c)] = P.stress[c][p];
      eps[6 * p + vtk_symmetric_component(c)] = P.strain[c][p];
    }
    rho[p] = P.mass[p] / P.volume[p];
    vol[p] = P.volume[p];
    ids[p] = P.id[p];
    bodies[p] = P.body[p];
    offset[p] = static_cast<vtkTypeInt32>(p);
    vertex[p] = static_cast<vtkTypeInt32>(p);
  }
  offsets->SetValue(n, static_cast<int>(n));

  vtkNew<vtkCellArray> cells;
  cells->SetData(offsets, connectivity);
  auto grid = vtkSmartPointer<vtkUnstructuredGrid>::New();
  grid->SetPoints(points);
  grid->SetCells(VTK_VERTEX, cells);
  vtkPointData* pd = grid->GetPointData();
  pd->AddArray(id);
  pd->AddArray(velocity);
  pd->AddArray(speed);
  pd->AddArray(stress);
  pd->AddArray(strain);
  pd->AddArray(density);
  pd->AddArray(volume);
  pd->AddArray(body);
  pd->SetActiveScalars("speed");
  return grid;
}

/// The VTK XML name of an array's element type ("Float64", "Int64", "UInt16", ...), as
/// vtkXMLWriter names it in the pieces.
std::string xml_type_name(vtkDataArray* a) {
  const int bits = 8 * a->GetDataTypeSize();
  switch (a->GetDataType()) {
    case VTK_FLOAT:
    case VTK_DOUBLE:
      return fmt::format("Float{}", bits);
    case VTK_CHAR:
    case VTK_SIGNED_CHAR:
    case VTK_SHORT:
    case VTK_INT:
    case VTK_LONG:
    case VTK_LONG_LONG:
    case VTK_ID_TYPE:
      return fmt::format("Int{}", bits);
    case VTK_UNSIGNED_CHAR:
    case VTK_UNSIGNED_SHORT:
    case VTK_UNSIGNED_INT:
    case VTK_UNSIGNED_LONG:
    case VTK_UNSIGNED_LONG_LONG:
      return fmt::format("UInt{}", bits);
    default:
      throw std::logic_error(fmt::format("no VTK XML type for array {}", a->GetName()));
  }
}

/// `text` with the five XML special characters escaped, for an attribute value.
std::string xml_escaped(const std::string& text) {
  std::string out;
  for (char c : text) {
    switch (c) {
      case '&': out += "&amp;"; break;
      case '<': out += "&lt;"; break;
      case '>': out += "&gt;"; break;
      case '"': out += "&quot;"; break;
      case '\'': out += "&apos;"; break;
      default: out += c;
    }
  }
  return out;
}

/// One <PDataArray/> of a .pvtu: the array's type, name, components and component names.
std::string pdata_array(vtkDataArray* a, const char* indent) {
  std::string xml = fmt::format("{}<PDataArray type=\"{}\" Name=\"{}\" NumberOfComponents=\"{}\"", indent,
                                xml_type_name(a), xml_escaped(a->GetName()), a->GetNumberOfComponents());
  for (int c = 0; c < a->GetNumberOfComponents(); ++c)
    if (const char* name = a->GetComponentName(c))
      xml += fmt::format(" ComponentName{}=\"{}\"", c, xml_escaped(name));
  return xml + "/>\n";
}

}  // namespace

std::vector<std::string> body_names(const Scene& scene) {
  std::vector<std::string> names;
  for (const auto& body : scene.bodies) names.push_back(body.name);
  return names;
}

void write_particles_vtu(const std::string& path, const ParticleStore& P, bool compress, std::optional<double> time,
                         const std::vector<std::string>& body_names) {
  ParticleFrame(P, time, body_names).write(path, compress);
}

std::size_t particle_frame_bytes(std::size_t particles, const std::vector<std::string>& body_names) {
  const ParticleStore layout;  // (particle_grid reads no particle of it: only the arrays are built)
  const vtkSmartPointer<vtkUnstructuredGrid> grid = particle_grid(layout, false);
  std::size_t per_particle = 3 * sizeof(double) + sizeof(vtkTypeInt32) * 2 + 1;  // point, connectivity and offset, cell type
  int arrays = 1 + 3 + 1;  // points, connectivity, offsets, types, and the field data's TimeValue
  vtkPointData* pd = grid->GetPointData();
  for (int i = 0; i < pd->GetNumberOfArrays(); ++i, ++arrays)
    per_particle += std::size_t(pd->GetArray(i)->GetDataTypeSize()) * std::size_t(pd->GetArray(i)->GetNumberOfComponents());
  // Each appended array has an 8-byte length header (UInt64, write_vtu_atomically); the XML that
  // describes them, about 180 bytes an array and 600 around them (VTK 9.1), is measured by
  // VtuOutput.FrameBytesEstimateMatchesAFrame.
  constexpr std::size_t kXmlPerArray = 180, kXmlFixed = 600;
  // body_names: a string array, its values each ended by a NUL byte, with a shorter tag than a
  // numeric array's (no range attributes: 150 bytes with its length header, measured likewise)
  std::size_t names = body_names.empty() ? 0 : 150;
  for (const std::string& name : body_names) names += name.size() + 1;
  return particles * per_particle + std::size_t(arrays) * (8 + kXmlPerArray) + kXmlFixed + sizeof(vtkTypeInt32) + names;
}

ParticleFrame::ParticleFrame(const ParticleStore& particles, std::optional<double> time,
                             const std::vector<std::string>& body_names)
    : grid_(particle_grid(particles, true)) {
  if (time) {
    vtkNew<vtkDoubleArray> value;  // the field ParaView reads a data set's time from
    value->SetName("TimeValue");
    value->SetNumberOfTuples(1);
    value->SetValue(0, *time);
    grid_->GetFieldData()->AddArray(value);
  }
  if (!body_names.empty()) {
    // The `body` point array holds indices (2 bytes a particle, not a name each): the names go
    // once in the field data, which every piece of a distributed frame carries and ParaView's
    // .pvtu reader passes on, so a user can tell which index is which body.
    vtkNew<vtkStringArray> names;
    names->SetName("body_names");
    names->SetNumberOfValues(static_cast<vtkIdType>(body_names.size()));
    for (std::size_t i = 0; i < body_names.size(); ++i) names->SetValue(static_cast<vtkIdType>(i), body_names[i]);
    grid_->GetFieldData()->AddArray(names);
  }
}
ParticleFrame::~ParticleFrame() = default;

void ParticleFrame::write(const std::string& path, bool compress) const {
  write_vtu_atomically(grid_, path, compress, "particle frame");
}

void write_particles_pvtu(const std::string& path, const std::vector<std::string>& piece_files,
                          const ParticleStore& layout) {
  const vtkSmartPointer<vtkUnstructuredGrid> grid = particle_grid(layout, false);
  vtkPointData* pd = grid->GetPointData();
  // The summary declares the pieces' arrays (vtkXMLPUnstructuredGridReader builds its output from
  // these declarations and copies each piece's values into them), then lists the pieces.
  std::string xml = fmt::format(
      "<?xml version=\"1.0\"?>\n"
      "<VTKFile type=\"PUnstructuredGrid\" version=\"0.1\" byte_order=\"{}\" header_type=\"UInt64\">\n"
      "  <PUnstructuredGrid GhostLevel=\"0\">\n",
      std::endian::native == std::endian::little ? "LittleEndian" : "BigEndian");
  xml += "    <PPointData";
  if (vtkDataArray* scalars = pd->GetScalars()) xml += fmt::format(" Scalars=\"{}\"", xml_escaped(scalars->GetName()));
  xml += ">\n";
  for (int i = 0; i < pd->GetNumberOfArrays(); ++i) xml += pdata_array(pd->GetArray(i), "      ");
  xml += "    </PPointData>\n";
  xml += "    <PPoints>\n";
  vtkDataArray* points = grid->GetPoints()->GetData();
  points->SetName("Points");  // the name vtkXMLWriter gives the point coordinates
  xml += pdata_array(points, "      ");
  xml += "    </PPoints>\n";
  for (const std::string& piece : piece_files) xml += fmt::format("    <Piece Source=\"{}\"/>\n", xml_escaped(piece));
  xml += "  </PUnstructuredGrid>\n</VTKFile>\n";
  write_file_atomically(path, xml);
}

void write_vtu_atomically(vtkUnstructuredGrid* grid, const std::string& path, bool compress, const char* what) {
  const std::string tmp = path + ".tmp";
  vtkNew<vtkXMLUnstructuredGridWriter> writer;
  writer->SetFileName(tmp.c_str());
  writer->SetInputData(grid);
  writer->SetDataModeToAppended();
  writer->EncodeAppendedDataOff();
  // 8-byte lengths: with VTK's 4-byte ones, a raw (uncompressed) array of more than 4 GiB is
  // refused ("Array is too large"), which the stress of a frame of 90 M particles reaches (6 doubles
  // a particle): 27 GB of particles, a run a 128 GB node holds. (ParaView reads either.)
  writer->SetHeaderTypeToUInt64();
  if (compress)
    writer->SetCompressorTypeToLZ4();
  else
    writer->SetCompressorTypeToNone();
  // A write that fails is talus's one-line error, with the system's reason (the error code holds
  // errno when the file could not be opened): VTK's own report was some twenty lines from three
  // objects of its pipeline, ahead of it. Its display is a process-wide switch, turned off once.
  static const bool vtk_reports_off = [] {
    vtkObject::GlobalWarningDisplayOff();
    return true;
  }();
  (void)vtk_reports_off;
  // Write() can return 1 when the file could not be opened (VTK 9.1 reports it through the
  // pipeline and the error code only): both are checked.
  const int written = writer->Write();
  const unsigned long code = writer->GetErrorCode();
  if (written != 1 || code != 0) {
    // (a partial file left behind took room a full disk needs for the run's record of the failure)
    std::error_code ignored;
    std::filesystem::remove(tmp, ignored);
    const char* reason = code != 0 ? vtkErrorCode::GetStringFromErrorCode(code) : nullptr;
    throw io_error(fmt::format("cannot write {} {}{}", what, path, reason && *reason ? std::string(": ") + reason : ""));
  }
  rename_into_place(tmp, path);
}

void PvdIndex::add(double time, const std::string& relative_file) {
  entries_.emplace_back(time, relative_file);
  write();
}

void PvdIndex::assign(std::vector<std::pair<double, std::string>> entries) {
  entries_ = std::move(entries);
  write();
}

void PvdIndex::write() const {
  if (!writes_file_) return;
  std::string xml =
      "<?xml version=\"1.0\"?>\n"
      "<VTKFile type=\"Collection\" version=\"0.1\" byte_order=\"LittleEndian\">\n"
      "  <Collection>\n";
  for (const auto& [t, file] : entries_)
    xml += fmt::format("    <DataSet timestep=\"{:.17g}\" group=\"\" part=\"0\" file=\"{}\"/>\n", t, file);
  xml += "  </Collection>\n</VTKFile>\n";
  write_file_atomically(path_, xml);
}

std::optional<bool> frame_stress_in_vtk_order(const std::string& path) {
  // The XML header comes before the appended data: its first kilobytes hold every array's tag.
  std::ifstream in(path, std::ios::binary);
  if (!in) return std::nullopt;
  std::string head(16384, '\0');
  in.read(head.data(), static_cast<std::streamsize>(head.size()));
  head.resize(static_cast<std::size_t>(in.gcount()));
  const std::size_t tag = head.find("Name=\"stress\"");
  if (tag == std::string::npos) return std::nullopt;
  const std::size_t end = head.find('>', tag);
  if (end == std::string::npos) return std::nullopt;
  return head.substr(tag, end - tag).find("ComponentName5=\"xz\"") != std::string::npos;
}

}  // namespace talus
