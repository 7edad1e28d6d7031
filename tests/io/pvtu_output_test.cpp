// The pieces of one frame, one per rank of a distributed run (one rank empty), and their .pvtu
// summary read back through VTK's parallel reader as one data set; the summary declares exactly
// the arrays the pieces hold.
#include "talus/io/vtu_writer.hpp"
#include "../support/scratch_dir.hpp"
#include "vtk_xml_headers.hpp"

#include <gtest/gtest.h>
#include <unistd.h>
#include <vtkDataArray.h>
#include <vtkNew.h>
#include <vtkPointData.h>
#include <vtkUnstructuredGrid.h>
#include <vtkXMLPUnstructuredGridReader.h>
#include <vtkXMLUnstructuredGridReader.h>

#include <filesystem>
#include <string>
#include <vector>

namespace talus {
namespace pvtu_output_test {
namespace {

namespace fs = std::filesystem;

/// n particles with ids first_id.., every field a different value (so a mixed-up piece shows).
ParticleStore store_of(std::int64_t first_id, std::size_t n) {
  ParticleStore P;
  for (std::size_t i = 0; i < n; ++i) {
    const double s = static_cast<double>(first_id) + static_cast<double>(i);
    P.add(first_id + static_cast<std::int64_t>(i), Vec3(0.1 * s, 0.2 + s, -0.3 * s), Vec3(s, -2.0 * s, 0.5),
          1.0 + s, 0.001 * (1.0 + s), static_cast<std::uint16_t>(i % 2));
    for (int c = 0; c < 6; ++c) {
      P.stress[c][i] = -1000.0 * s - c;
      P.strain[c][i] = 1e-3 * s + c;
    }
  }
  return P;
}

vtkSmartPointer<vtkUnstructuredGrid> read_vtu(const fs::path& path) {
  vtkNew<vtkXMLUnstructuredGridReader> reader;
  reader->SetFileName(path.string().c_str());
  reader->Update();
  return reader->GetOutput();
}

/// Name and number of components of every point array, in order.
std::vector<std::pair<std::string, int>> point_arrays(vtkUnstructuredGrid* grid) {
  std::vector<std::pair<std::string, int>> out;
  vtkPointData* pd = grid->GetPointData();
  for (int i = 0; i < pd->GetNumberOfArrays(); ++i)
    out.emplace_back(pd->GetArrayName(i), pd->GetArray(i)->GetNumberOfComponents());
  return out;
}

struct Pieces {
  test::ScratchDir dir;
  std::vector<ParticleStore> stores;
  std::vector<std::string> files;  // relative to dir
};

/// Three ranks' pieces, the middle rank empty, written raw or with LZ4.
Pieces write_pieces(const std::string& name, bool compress) {
  Pieces p{test::ScratchDir("test_" + name), {}, {}};
  p.stores.push_back(store_of(0, 5));
  p.stores.push_back(ParticleStore{});
  p.stores.push_back(store_of(100, 7));
  for (std::size_t r = 0; r < p.stores.size(); ++r) {
    p.files.push_back("frame_000003_000" + std::to_string(r) + ".vtu");
    write_particles_vtu((p.dir / p.files.back()).string(), p.stores[r], compress);
  }
  return p;
}

TEST(PvtuOutput, EmptyStoreWritesAValidPieceWithAllArrays) {
  const test::ScratchDir dir("test_empty_piece");
  const ParticleStore empty;
  const ParticleStore full = store_of(0, 4);
  write_particles_vtu((dir / "empty.vtu").string(), empty, false);
  write_particles_vtu((dir / "full.vtu").string(), full, false);
  vtkSmartPointer<vtkUnstructuredGrid> grid = read_vtu(dir / "empty.vtu");
  ASSERT_NE(grid, nullptr);
  EXPECT_EQ(grid->GetNumberOfPoints(), 0);
  EXPECT_EQ(grid->GetNumberOfCells(), 0);
  EXPECT_EQ(point_arrays(grid), point_arrays(read_vtu(dir / "full.vtu")));
  EXPECT_EQ(point_arrays(grid).size(), 8u);
  // The same declarations, as text, as a piece with particles.
  EXPECT_EQ(test::array_declarations(test::xml_section(test::vtu_header(dir / "empty.vtu"), "PointData"), "DataArray"),
            test::array_declarations(test::xml_section(test::vtu_header(dir / "full.vtu"), "PointData"), "DataArray"));
}

TEST(PvtuOutput, SummaryDeclaresExactlyThePiecesArrays) {
  const Pieces p = write_pieces("pvtu_header", false);
  const fs::path pvtu = p.dir / "frame_000003.pvtu";
  write_particles_pvtu(pvtu.string(), p.files, p.stores[0]);
  const std::string summary = test::file_bytes(pvtu);
  EXPECT_NE(summary.find("type=\"PUnstructuredGrid\""), std::string::npos);
  const auto grid_elements = test::xml_elements(summary, "PUnstructuredGrid");
  ASSERT_EQ(grid_elements.size(), 1u);
  EXPECT_EQ(grid_elements[0].at("GhostLevel"), "0");

  const auto declared_points = test::array_declarations(test::xml_section(summary, "PPointData"), "PDataArray");
  const auto declared_coordinates = test::array_declarations(test::xml_section(summary, "PPoints"), "PDataArray");
  ASSERT_EQ(declared_points.size(), 8u);
  ASSERT_EQ(declared_coordinates.size(), 1u);
  EXPECT_EQ(declared_coordinates[0].type, "Float64");
  EXPECT_EQ(declared_coordinates[0].components, "3");
  for (const std::string& file : p.files) {
    const std::string header = test::vtu_header(p.dir / file);
    EXPECT_EQ(declared_points, test::array_declarations(test::xml_section(header, "PointData"), "DataArray")) << file;
    EXPECT_EQ(declared_coordinates, test::array_declarations(test::xml_section(header, "Points"), "DataArray")) << file;
  }
  // The active scalars of the pieces stay active in the whole.
  EXPECT_EQ(test::xml_elements(summary, "PPointData").at(0).at("Scalars"),
            test::xml_elements(test::vtu_header(p.dir / p.files[0]), "PointData").at(0).at("Scalars"));

  std::vector<std::string> sources;
  for (const auto& piece : test::xml_elements(summary, "Piece")) sources.push_back(piece.at("Source"));
  EXPECT_EQ(sources, p.files);

  // The layout's particles are not read: an empty store of the same arrays gives the same summary.
  write_particles_pvtu((p.dir / "from_empty.pvtu").string(), p.files, ParticleStore{});
  EXPECT_EQ(test::file_bytes(p.dir / "from_empty.pvtu"), summary);
  for (const auto& entry : fs::directory_iterator(p.dir)) EXPECT_NE(entry.path().extension(), ".tmp");
}

TEST(PvtuOutput, PiecesReadBackAsOneDataSet) {
  for (bool compress : {false, true}) {
    const Pieces p = write_pieces(compress ? "pvtu_lz4" : "pvtu_raw", compress);
    const fs::path pvtu = p.dir / "frame_000003.pvtu";
    write_particles_pvtu(pvtu.string(), p.files, p.stores[0]);

    vtkNew<vtkXMLPUnstructuredGridReader> reader;
    reader->SetFileName(pvtu.string().c_str());
    reader->Update();
    vtkUnstructuredGrid* whole = reader->GetOutput();
    ASSERT_NE(whole, nullptr);
    EXPECT_EQ(reader->GetNumberOfPieces(), 3);

    std::size_t total = 0;
    for (const auto& store : p.stores) total += store.size();
    ASSERT_EQ(total, 12u);
    ASSERT_EQ(whole->GetNumberOfPoints(), static_cast<vtkIdType>(total));
    EXPECT_EQ(whole->GetNumberOfCells(), static_cast<vtkIdType>(total));
    for (const std::string& file : p.files)
      EXPECT_EQ(point_arrays(whole), point_arrays(read_vtu(p.dir / file))) << file;
    EXPECT_EQ(std::string(whole->GetPointData()->GetScalars()->GetName()), "speed");

    // Every particle, in rank order, with its values.
    vtkPointData* pd = whole->GetPointData();
    vtkIdType at = 0;
    for (const auto& P : p.stores) {
      for (std::size_t i = 0; i < P.size(); ++i, ++at) {
        EXPECT_EQ(pd->GetArray("id")->GetTuple1(at), static_cast<double>(P.id[i]));
        double x[3];
        whole->GetPoint(at, x);
        for (int d = 0; d < 3; ++d) EXPECT_EQ(x[d], P.x[d][i]);
        EXPECT_EQ(pd->GetArray("stress")->GetComponent(at, vtk_symmetric_component(XZ)), P.stress[XZ][i]);
        EXPECT_EQ(pd->GetArray("strain")->GetComponent(at, vtk_symmetric_component(YY)), P.strain[YY][i]);
        EXPECT_EQ(pd->GetArray("body")->GetTuple1(at), P.body[i]);
        EXPECT_EQ(pd->GetArray("density")->GetTuple1(at), P.mass[i] / P.volume[i]);
      }
    }
    EXPECT_EQ(std::string(pd->GetArray("stress")->GetComponentName(vtk_symmetric_component(XY))), "xy");
  }
}

TEST(PvtuOutput, PvdIndexOfAnotherRankWritesNothing) {
  const test::ScratchDir dir("test_pvd_flag");
  PvdIndex silent((dir / "silent.pvd").string(), false);
  PvdIndex index((dir / "index.pvd").string());
  for (PvdIndex* pvd : {&silent, &index}) {
    pvd->add(0.0, "frames/particles_000000.pvtu");
    pvd->add(0.5, "frames/particles_000001.pvtu");
  }
  EXPECT_EQ(silent.size(), 2u);
  EXPECT_FALSE(silent.writes_file());
  EXPECT_FALSE(fs::exists(dir / "silent.pvd"));
  const std::string text = test::file_bytes(dir / "index.pvd");
  const auto data_sets = test::xml_elements(text, "DataSet");
  ASSERT_EQ(data_sets.size(), 2u);
  EXPECT_EQ(data_sets[1].at("file"), "frames/particles_000001.pvtu");
  EXPECT_EQ(data_sets[1].at("timestep"), "0.5");
}

}  // namespace
}  // namespace pvtu_output_test
}  // namespace talus
