// A frame written by the solver's writer reads back through VTK's own reader with the right arrays,
// and the run driver writes a .pvd index, the resolved scene and the energy history.
#include "../solver/scene_fixtures.hpp"
#include "../support/scratch_dir.hpp"
#include "talus/driver/run_driver.hpp"
#include "talus/driver/run_outputs.hpp"
#include "talus/io/atomic_file.hpp"
#include "talus/io/vtu_writer.hpp"
#include "vtk_xml_headers.hpp"
#include "talus/solver/solver.hpp"

#include <gtest/gtest.h>
#include <vtkDataArray.h>
#include <vtkFieldData.h>
#include <vtkNew.h>
#include <vtkPointData.h>
#include <vtkStringArray.h>
#include <vtkUnstructuredGrid.h>
#include <vtkXMLUnstructuredGridReader.h>

#include <sys/stat.h>

#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>
#include <thread>
#include <vector>

namespace talus {
namespace vtu_output_test {
namespace {

namespace fs = std::filesystem;

using test::ScratchDir;

/// run_scene on `scene` into `dir`, without a progress line.
RunSummary run_quietly(const Scene& scene, const fs::path& dir) {
  Solver solver(scene);
  RunOptions options;
  options.out_dir = dir.string();
  options.progress = false;
  return run_scene(solver, options);
}

TEST(VtuOutput, FrameReadsBackWithAllArrays) {
  Solver solver(test::tumbling_block_scene(0.01));
  while (!solver.finished()) solver.step();
  const ScratchDir dir("test_vtu");
  for (bool compress : {false, true}) {
    const std::string path = (dir / (compress ? "lz4.vtu" : "raw.vtu")).string();
    write_particles_vtu(path, solver.particles(), compress);
    vtkNew<vtkXMLUnstructuredGridReader> reader;
    reader->SetFileName(path.c_str());
    reader->Update();
    vtkUnstructuredGrid* grid = reader->GetOutput();
    const auto& P = solver.particles();
    ASSERT_EQ(grid->GetNumberOfPoints(), static_cast<vtkIdType>(P.size()));
    ASSERT_EQ(grid->GetNumberOfCells(), static_cast<vtkIdType>(P.size()));
    vtkPointData* pd = grid->GetPointData();
    const std::pair<const char*, int> arrays[] = {{"id", 1},     {"velocity", 3}, {"speed", 1}, {"stress", 6},
                                                  {"strain", 6}, {"density", 1},  {"volume", 1}, {"body", 1}};
    for (const auto& [name, components] : arrays) {
      vtkDataArray* a = pd->GetArray(name);
      ASSERT_NE(a, nullptr) << name;
      EXPECT_EQ(a->GetNumberOfComponents(), components) << name;
    }
    const std::size_t p = P.size() / 3;
    double x[3];
    grid->GetPoint(static_cast<vtkIdType>(p), x);
    for (int d = 0; d < 3; ++d) EXPECT_EQ(x[d], P.x[d][p]);
    // VTK's order of a symmetric tensor: xx yy zz xy yz xz, each component named
    for (int c = 0; c < 6; ++c)
      EXPECT_EQ(pd->GetArray("stress")->GetComponent(static_cast<vtkIdType>(p), vtk_symmetric_component(c)),
                P.stress[c][p]);
    EXPECT_EQ(vtk_symmetric_component(XY), 3);
    EXPECT_EQ(vtk_symmetric_component(YZ), 4);
    EXPECT_EQ(vtk_symmetric_component(XZ), 5);
    EXPECT_EQ(std::string(pd->GetArray("strain")->GetComponentName(3)), "xy");
    EXPECT_EQ(std::string(pd->GetArray("strain")->GetComponentName(5)), "xz");
    EXPECT_EQ(pd->GetArray("id")->GetTuple1(static_cast<vtkIdType>(p)), static_cast<double>(P.id[p]));
    EXPECT_DOUBLE_EQ(pd->GetArray("density")->GetTuple1(static_cast<vtkIdType>(p)), P.mass[p] / P.volume[p]);
  }
}

// Frames declare 8-byte array lengths: VTK 9.1 refuses a raw array over 4 GiB under its 4-byte
// ones ("Array is too large.  Set HeaderType to UInt64", checked with a 4.4 GB array), which an
// uncompressed frame of 90 M particles holds in its stress. A 4 GiB array is too big for this
// suite, so the test reads the declaration that allows it.
TEST(VtuOutput, FramesDeclareLengthsThatHoldArraysOverFourGiB) {
  Solver solver(test::tumbling_block_scene(0.01));
  const ScratchDir dir("test_vtu_header");
  for (bool compress : {false, true}) {
    const fs::path path = dir / (compress ? "lz4.vtu" : "raw.vtu");
    write_particles_vtu(path.string(), solver.particles(), compress, 0.0);
    const std::vector<test::XmlAttributes> file = test::xml_elements(test::file_bytes(path), "VTKFile");
    ASSERT_EQ(file.size(), 1u) << path;
    EXPECT_EQ(file[0].at("header_type"), "UInt64") << path;
  }
}

// particle_frame_bytes, the disk-use estimate of `talus check` and `talus run`, against the files:
// an uncompressed frame (with its time and body names, as the runs write them) within 64 bytes,
// whatever its particle count; a compressed one no larger but for its block headers.
TEST(VtuOutput, FrameBytesEstimateMatchesAFrame) {
  Solver solver(test::tumbling_block_scene(0.01));
  const ScratchDir dir("test_vtu_bytes");
  ParticleStore none;
  for (const ParticleStore* store : {&solver.particles(), static_cast<const ParticleStore*>(&none)}) {
    for (bool compress : {false, true}) {
      const fs::path path = dir / (compress ? "lz4.vtu" : "raw.vtu");
      const std::vector<std::string> names = {"block", "a body with a longer name", "c"};
      write_particles_vtu(path.string(), *store, compress, 0.125, names);
      const auto actual = static_cast<double>(fs::file_size(path));
      const auto estimate = static_cast<double>(particle_frame_bytes(store->size(), names));
      if (compress)  // (each compressed array's block header, 4 UInt64, is 24 bytes longer than a raw one's: 14 arrays)
        EXPECT_LE(actual, estimate + 14 * 24) << store->size() << " particles";
      else
        EXPECT_NEAR(actual, estimate, 64.0) << store->size() << " particles";
    }
  }
}

TEST(VtuOutput, RunWritesSeriesIndexSceneAndHistory) {
  Scene scene = test::tumbling_block_scene(0.02);
  scene.output.frame_interval = 0.005;
  const ScratchDir scratch("test_run");
  const fs::path dir = scratch / "out";  // the run makes its folder
  const RunSummary summary = run_quietly(scene, dir);
  EXPECT_EQ(summary.frames, 5u);  // t = 0, 0.005, 0.01, 0.015, 0.02
  std::ifstream pvd(dir / "particles.pvd");
  std::stringstream text;
  text << pvd.rdbuf();
  EXPECT_NE(text.str().find("type=\"Collection\""), std::string::npos);
  EXPECT_NE(text.str().find("frames/particles_000004.vtu"), std::string::npos);
  // each frame carries its time (TimeValue, as ParaView reads it), the time the .pvd lists for it
  std::vector<double> listed;
  for (std::size_t at = text.str().find("timestep=\""); at != std::string::npos; at = text.str().find("timestep=\"", at + 1))
    listed.push_back(std::stod(text.str().substr(at + 10)));
  ASSERT_EQ(listed.size(), 5u);
  for (int f = 0; f < 5; ++f) {
    const fs::path frame = dir / "frames" / ("particles_00000" + std::to_string(f) + ".vtu");
    ASSERT_TRUE(fs::exists(frame));
    vtkNew<vtkXMLUnstructuredGridReader> reader;
    reader->SetFileName(frame.string().c_str());
    reader->Update();
    vtkDataArray* time = reader->GetOutput()->GetFieldData()->GetArray("TimeValue");
    ASSERT_NE(time, nullptr) << frame;
    EXPECT_EQ(time->GetTuple1(0), listed[f]) << frame;
    // and the bodies' names, name i for the `body` index i (the frames gave indices alone)
    auto* names = vtkStringArray::SafeDownCast(reader->GetOutput()->GetFieldData()->GetAbstractArray("body_names"));
    ASSERT_NE(names, nullptr) << frame;
    ASSERT_EQ(names->GetNumberOfValues(), static_cast<vtkIdType>(scene.bodies.size())) << frame;
    for (std::size_t b = 0; b < scene.bodies.size(); ++b) EXPECT_EQ(std::string(names->GetValue(b)), scene.bodies[b].name) << frame;
  }
  EXPECT_EQ(summary.frames_in_series, 5u);
  EXPECT_TRUE(fs::exists(dir / "scene.json"));
  std::ifstream csv(dir / "energy.csv");
  std::string header;
  std::getline(csv, header);
  EXPECT_EQ(header, "time,step,dt,kinetic,strain,gravity,friction_work,plastic_work,outflow,damping,gravity_ramp,total");
  int rows = 0;
  for (std::string line; std::getline(csv, line);) ++rows;
  EXPECT_EQ(rows, summary.steps + 1);
  // No temporary file is left behind.
  for (const auto& entry : fs::recursive_directory_iterator(dir)) EXPECT_NE(entry.path().extension(), ".tmp");
}

// frames_of_run (the disk estimate's frame count) against the frames runs write: intervals that
// divide the end time, that do not, that exceed it, and none.
TEST(VtuOutput, FramesOfRunCountsTheFramesARunWrites) {
  for (const double interval : {0.005, 0.003, 0.02, 0.03, 0.0}) {
    Scene scene = test::tumbling_block_scene(0.02);
    scene.output.frame_interval = interval;
    const ScratchDir scratch("test_frames_of_run");
    const fs::path dir = scratch / "out";  // the run makes its folder
    const RunSummary summary = run_quietly(scene, dir);
    EXPECT_EQ(summary.frames, frames_of_run(scene)) << "frame_interval " << interval;
  }
  // A vanishing interval (allowed: a frame every step) is capped, not overflowed: by the interval at
  // 10^15, and by one frame a step at the steps estimated at the initial time step (end 1 s,
  // frame_interval 1e-5 s counted 100 001 frames where a run wrote 227).
  Scene every_step = test::tumbling_block_scene(1e6);
  every_step.output.frame_interval = 1e-300;
  EXPECT_EQ(frames_by_interval(every_step), std::size_t(1e15));
  EXPECT_EQ(frames_of_run(every_step), std::size_t(estimated_steps(every_step)) + 1);
  EXPECT_LT(frames_of_run(every_step), std::size_t(1e15));
  // A run with a frame every step writes one a step: its steps and the first (this block spins at a
  // steady rate, so the steps are those estimated at the start).
  Scene short_interval = test::tumbling_block_scene(0.02);
  short_interval.output.frame_interval = 1e-9;
  const ScratchDir scratch("test_frames_of_run_steps");
  const fs::path dir = scratch / "out";  // the run makes its folder
  const RunSummary summary = run_quietly(short_interval, dir);
  EXPECT_EQ(summary.frames, std::size_t(summary.steps) + 1);
  EXPECT_LT(frames_of_run(short_interval), frames_by_interval(short_interval));
  EXPECT_NEAR(double(frames_of_run(short_interval)), double(summary.frames), 0.02 * double(summary.frames));
}

// A whole-file write (the run's records, element-test's CSV) goes through a temporary file and a
// rename, which replaced whatever the path named: `-o link.csv` swapped the link for a file, and a
// FIFO or a device (`-o /dev/null`, `/dev/stdout`, as root) became a regular file. It writes
// through those, and through a link replaces the file the link names.
TEST(VtuOutput, WholeFileWritesKeepLinksAndWriteThroughPipesAndDevices) {
  const ScratchDir dir("test_write_through");
  const auto read = [](const fs::path& p) {
    std::ifstream in(p);
    return std::string((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  };
  {
    std::ofstream(dir / "target.csv") << "old\n";
  }
  fs::create_symlink("target.csv", dir / "link.csv");
  write_file_atomically((dir / "link.csv").string(), "new\n");
  EXPECT_TRUE(fs::is_symlink(fs::symlink_status(dir / "link.csv")));
  EXPECT_EQ(read(dir / "target.csv"), "new\n");
  // a named pipe: the text reaches its reader, and the pipe stays a pipe
  const fs::path fifo = dir / "fifo";
  ASSERT_EQ(::mkfifo(fifo.c_str(), 0600), 0);
  std::string received;
  std::thread reader([&] { received = read(fifo); });
  write_file_atomically(fifo.string(), "through the pipe\n");
  reader.join();
  EXPECT_EQ(received, "through the pipe\n");
  EXPECT_EQ(fs::status(fifo).type(), fs::file_type::fifo);
  write_file_atomically("/dev/null", "nothing\n");
  EXPECT_EQ(fs::status("/dev/null").type(), fs::file_type::character);
  for (const auto& entry : fs::directory_iterator(dir)) EXPECT_NE(entry.path().extension(), ".tmp");
}

}  // namespace
}  // namespace vtu_output_test
}  // namespace talus
