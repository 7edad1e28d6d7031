#include "talus/io/vtu_writer.hpp"

#include "talus/core/error.hpp"

#include <fmt/core.h>
#include <vtkCellArray.h>
#include <vtkCellType.h>
#include <vtkDoubleArray.h>
#include <vtkNew.h>
#include <vtkPointData.h>
#include <vtkPoints.h>
#include <vtkTypeInt32Array.h>
#include <vtkTypeInt64Array.h>
#include <vtkUnsignedShortArray.h>
#include <vtkUnstructuredGrid.h>
#include <vtkXMLUnstructuredGridWriter.h>

#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>

namespace talus {

namespace {

vtkNew<vtkDoubleArray> make_array(const char* name, int components, vtkIdType n) {
  vtkNew<vtkDoubleArray> a;
  a->SetName(name);
  a->SetNumberOfComponents(components);
  a->SetNumberOfTuples(n);
  return a;
}

void name_voigt_components(vtkDoubleArray* a) {
  const char* names[6] = {"xx", "yy", "zz", "yz", "xz", "xy"};
  for (int c = 0; c < 6; ++c) a->SetComponentName(c, names[c]);
}

}  // namespace

void write_particles_vtu(const std::string& path, const ParticleStore& P, bool compress) {
  const auto n = static_cast<vtkIdType>(P.size());
  vtkNew<vtkPoints> points;
  points->SetDataTypeToDouble();
  points->SetNumberOfPoints(n);
  auto velocity = make_array("velocity", 3, n);
  auto speed = make_array("speed", 1, n);
  auto stress = make_array("stress", 6, n);
  auto strain = make_array("strain", 6, n);
  auto density = make_array("density", 1, n);
  auto volume = make_array("volume", 1, n);
  name_voigt_components(stress);
  name_voigt_components(strain);
  vtkNew<vtkTypeInt64Array> id;
  id->SetName("id");
  id->SetNumberOfTuples(n);
  vtkNew<vtkUnsignedShortArray> body;
  body->SetName("body");
  body->SetNumberOfTuples(n);
  vtkNew<vtkTypeInt32Array> offsets, connectivity;
  offsets->SetNumberOfTuples(n + 1);
  connectivity->SetNumberOfTuples(n);

  for (vtkIdType p = 0; p < n; ++p) {
    points->SetPoint(p, P.x[0][p], P.x[1][p], P.x[2][p]);
    double v2 = 0.0;
    for (int d = 0; d < 3; ++d) {
      velocity->SetTypedComponent(p, d, P.v[d][p]);
      v2 += P.v[d][p] * P.v[d][p];
    }
    speed->SetValue(p, std::sqrt(v2));
    for (int c = 0; c < 6; ++c) {
      stress->SetTypedComponent(p, c, P.stress[c][p]);
      strain->SetTypedComponent(p, c, P.strain[c][p]);
    }
    density->SetValue(p, P.mass[p] / P.volume[p]);
    volume->SetValue(p, P.volume[p]);
    id->SetValue(p, P.id[p]);
    body->SetValue(p, P.body[p]);
    offsets->SetValue(p, static_cast<int>(p));
    connectivity->SetValue(p, static_cast<int>(p));
  }
  offsets->SetValue(n, static_cast<int>(n));

  vtkNew<vtkCellArray> cells;
  cells->SetData(offsets, connectivity);
  vtkNew<vtkUnstructuredGrid> grid;
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

  write_vtu_atomically(grid, path, compress, "particle frame");
}

void write_vtu_atomically(vtkUnstructuredGrid* grid, const std::string& path, bool compress, const char* what) {
  const std::string tmp = path + ".tmp";
  vtkNew<vtkXMLUnstructuredGridWriter> writer;
  writer->SetFileName(tmp.c_str());
  writer->SetInputData(grid);
  writer->SetDataModeToAppended();
  writer->EncodeAppendedDataOff();
  if (compress)
    writer->SetCompressorTypeToLZ4();
  else
    writer->SetCompressorTypeToNone();
  if (writer->Write() != 1) throw io_error(fmt::format("cannot write {} {}", what, path));
  std::filesystem::rename(tmp, path);
}

void write_file_atomically(const std::string& path, const std::string& text) {
  const std::string tmp = path + ".tmp";
  {
    std::ofstream out(tmp, std::ios::binary | std::ios::trunc);
    out << text;
    out.flush();
    if (!out) throw io_error(fmt::format("cannot write {}", path));
  }
  std::filesystem::rename(tmp, path);
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
  std::string xml =
      "<?xml version=\"1.0\"?>\n"
      "<VTKFile type=\"Collection\" version=\"0.1\" byte_order=\"LittleEndian\">\n"
      "  <Collection>\n";
  for (const auto& [t, file] : entries_)
    xml += fmt::format("    <DataSet timestep=\"{:.17g}\" group=\"\" part=\"0\" file=\"{}\"/>\n", t, file);
  xml += "  </Collection>\n</VTKFile>\n";
  write_file_atomically(path_, xml);
}

}  // namespace talus
