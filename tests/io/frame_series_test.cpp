// The frame series of a run: one rank writes .vtu frames exactly as write_particles_vtu does, of
// the particles as they were when write() was called although the file is written in the
// background; the ranks of a distributed run write one piece each and rank 0 a .pvtu that reads
// back as one data set; a resumed run keeps the frames of either kind its checkpoint lists and no
// other; a write that fails in the background stops the run at the next complete().
#include "../solver/scene_fixtures.hpp"
#include "../support/scratch_dir.hpp"
#include "talus/core/comm.hpp"
#include "talus/core/error.hpp"
#include "talus/driver/run_outputs.hpp"
#include "talus/solver/solver.hpp"
#include "vtk_xml_headers.hpp"

#include <gtest/gtest.h>
#include <unistd.h>
#include <vtkDataArray.h>
#include <vtkNew.h>
#include <vtkPointData.h>
#include <vtkUnstructuredGrid.h>
#include <vtkXMLPUnstructuredGridReader.h>
#include <vtkXMLUnstructuredGridReader.h>

#include <algorithm>
#include <filesystem>
#include <fstream>
#include <optional>
#include <set>
#include <string>
#include <vector>

namespace talus {
namespace frame_series_test {
namespace {

namespace fs = std::filesystem;

using test::ScratchDir;

/// The names of the files in `dir`, sorted.
std::vector<std::string> files_in(const fs::path& dir) {
  std::vector<std::string> names;
  for (const auto& entry : fs::directory_iterator(dir)) names.push_back(entry.path().filename().string());
  std::sort(names.begin(), names.end());
  return names;
}

/// The files the .pvd lists, in order.
std::vector<std::string> pvd_files(const fs::path& pvd) {
  std::vector<std::string> files;
  for (const auto& data_set : test::xml_elements(test::file_bytes(pvd), "DataSet"))
    files.push_back(data_set.at("file"));
  return files;
}

void touch(const fs::path& path) { std::ofstream(path) << "x"; }

// An output schedule moves its next time past the time just written: by whole intervals when the
// interval is usable, and to the next representable time when it is far below the time step or
// below t's rounding step (such intervals used to hang the run in this loop).
TEST(OutputSchedule, AdvancesByWholeIntervalsAndNeverHangsOnATinyInterval) {
  double next = 0.0;
  OutputSchedule usual{0.01, next};
  usual.advance_past(0.0);
  EXPECT_EQ(next, 0.01);
  usual.advance_past(0.0345);
  EXPECT_EQ(next, 0.01 + 0.01 + 0.01 + 0.01);
  for (double tiny : {1e-9, 1e-20, 1e-300}) {
    SCOPED_TRACE(tiny);
    double due = 0.0;
    OutputSchedule schedule{tiny, due};
    for (double t : {1.0e-4, 2.5e-4, 3.7}) {
      ASSERT_TRUE(schedule.reached(t));
      schedule.advance_past(t);
      EXPECT_GT(due, t);
      EXPECT_LE(due, t + 64 * tiny + t * 1e-15);  // at the latest at the next step
    }
  }
  double none = 0.0;
  OutputSchedule off{0.0, none};
  off.advance_past(5.0);
  EXPECT_EQ(none, 0.0);
  EXPECT_FALSE(off.reached(5.0));
}

TEST(FrameSeries, NamesFramesSummariesAndPieces) {
  EXPECT_EQ(frame_name(7), "frames/particles_000007.vtu");
  EXPECT_EQ(frame_name(7, false), "frames/particles_000007.vtu");
  EXPECT_EQ(frame_name(7, true), "frames/particles_000007.pvtu");
  EXPECT_EQ(frame_piece_name(7, 3), "frames/particles_000007_0003.vtu");
  EXPECT_EQ(frame_piece_name(123456, 1023), "frames/particles_123456_1023.vtu");
}

TEST(FrameSeries, OneRankWritesVtuFramesAsWriteParticlesVtuDoes) {
  for (bool compress : {false, true}) {
    Solver solver(test::tumbling_block_scene(0.01));
    const ScratchDir scratch(compress ? "test_series_lz4" : "test_series_raw");
    const fs::path dir = scratch / "out";  // prepare_output_folder makes it
    prepare_output_folder(dir, nullptr);
    RunProgress progress;
    FrameSeries frames(dir, compress, progress, Comm());
    EXPECT_EQ(frames.write(solver), "frames/particles_000000.vtu");
    for (int s = 0; s < 5; ++s) solver.step();
    // The file the frame must be: write_particles_vtu's, of the particles when write() is called.
    write_particles_vtu((dir / "expected.vtu").string(), solver.particles(), compress, solver.time(),
                        body_names(solver.scene()));
    EXPECT_EQ(frames.write(solver), "frames/particles_000001.vtu");
    EXPECT_TRUE(frames.has_frame_of_step(5));
    ASSERT_EQ(progress.frame_times.size(), 2u);
    EXPECT_EQ(progress.frame_times[1], solver.time());
    // The solver goes on while the frame is written: the frame keeps the state it was given.
    for (int s = 0; s < 5; ++s) solver.step();
    frames.complete(solver);

    // Byte for byte the file write_particles_vtu writes; no summary, no pieces.
    EXPECT_EQ(test::file_bytes(dir / "frames" / "particles_000001.vtu"), test::file_bytes(dir / "expected.vtu"));
    EXPECT_EQ(files_in(dir / "frames"), (std::vector<std::string>{"particles_000000.vtu", "particles_000001.vtu"}));
    EXPECT_EQ(pvd_files(frames.pvd_path()),
              (std::vector<std::string>{"frames/particles_000000.vtu", "frames/particles_000001.vtu"}));
  }
}

TEST(FrameSeries, ResumeKeepsTheListedFramesOfEveryKindAndNoOther) {
  const ScratchDir dir("test_resume_frames");
  fs::create_directories(dir / "frames");
  // Frame 0 by one rank, frame 1 by two, frame 2 by three ranks, frame 3 by one; a killed writer's
  // temporary file; files of the user's (a .vtu among them: only talus's frame names are removed).
  for (const char* f : {"particles_000000.vtu", "particles_000001.pvtu", "particles_000001_0000.vtu",
                        "particles_000001_0001.vtu", "particles_000002.pvtu", "particles_000002_0000.vtu",
                        "particles_000002_0001.vtu", "particles_000002_0002.vtu", "particles_000003.vtu",
                        "particles_000004.vtu.tmp", "notes.txt", "mesh.vtu"})
    touch(dir / "frames" / f);
  RunProgress resume;
  resume.frame_times = {0.0, 0.1};
  resume.frame_steps = {0, 10};
  prepare_output_folder(dir, &resume);
  EXPECT_EQ(files_in(dir / "frames"),
            (std::vector<std::string>{"mesh.vtu", "notes.txt", "particles_000000.vtu", "particles_000001.pvtu",
                                      "particles_000001_0000.vtu", "particles_000001_0001.vtu"}));

  // The resumed series lists each kept frame under the kind on disk, and goes on in its own kind.
  FrameSeries frames(dir, false, resume, Comm());
  EXPECT_EQ(pvd_files(frames.pvd_path()),
            (std::vector<std::string>{"frames/particles_000000.vtu", "frames/particles_000001.pvtu"}));
  Solver solver(test::tumbling_block_scene(0.01));
  EXPECT_EQ(frames.write(solver), "frames/particles_000002.vtu");
  frames.complete(solver);
  EXPECT_EQ(pvd_files(frames.pvd_path()).back(), "frames/particles_000002.vtu");

  // Resumed into another folder (--restart with --out), the series lists none of the checkpoint's
  // earlier frames, which are not there, and its own frames take the next indices.
  const ScratchDir elsewhere_scratch("test_resume_elsewhere");
  const fs::path elsewhere = elsewhere_scratch / "out";  // prepare_output_folder makes it
  RunProgress resumed_elsewhere;  // the checkpoint's two frames (`resume` has the series' third by now)
  resumed_elsewhere.frame_times = {0.0, 0.1};
  resumed_elsewhere.frame_steps = {0, 10};
  prepare_output_folder(elsewhere, &resumed_elsewhere);
  FrameSeries other(elsewhere, false, resumed_elsewhere, Comm());
  EXPECT_FALSE(fs::exists(other.pvd_path()));
  EXPECT_EQ(other.write(solver), "frames/particles_000002.vtu");
  other.complete(solver);
  EXPECT_EQ(pvd_files(other.pvd_path()), (std::vector<std::string>{"frames/particles_000002.vtu"}));

  // A fresh run removes every frame, summary and piece.
  prepare_output_folder(dir, nullptr);
  EXPECT_EQ(files_in(dir / "frames"), (std::vector<std::string>{"mesh.vtu", "notes.txt"}));  // the user's files stay
  EXPECT_FALSE(fs::exists(dir / "particles.pvd"));
}

/// The tumbling block's solver and a fresh output folder for one series (removed at the end).
struct OneRankSeries {
  explicit OneRankSeries(const char* name) : scratch(std::string("test_") + name) { prepare_output_folder(dir, nullptr); }
  Solver solver{test::tumbling_block_scene(0.01)};
  ScratchDir scratch;
  fs::path dir = scratch / "out";  // prepare_output_folder makes it
  RunProgress progress;
};

TEST(FrameSeries, WithoutBackgroundEveryFrameIsOnDiskAndListedWhenWriteReturns) {
  OneRankSeries s("series_foreground");
  FrameSeries frames(s.dir, true, s.progress, Comm(), false);
  write_particles_vtu((s.dir / "expected.vtu").string(), s.solver.particles(), true, s.solver.time(),
                      body_names(s.solver.scene()));
  EXPECT_EQ(frames.write(s.solver), "frames/particles_000000.vtu");
  EXPECT_EQ(test::file_bytes(s.dir / "frames" / "particles_000000.vtu"), test::file_bytes(s.dir / "expected.vtu"));
  EXPECT_EQ(pvd_files(frames.pvd_path()), std::vector<std::string>{"frames/particles_000000.vtu"});
}

TEST(FrameSeries, AFailedBackgroundWriteIsReportedAndNotListed) {
  OneRankSeries s("series_failed_write");
  Solver& solver = s.solver;
  const fs::path& dir = s.dir;
  FrameSeries frames(dir, false, s.progress, Comm());
  fs::remove_all(dir / "frames");  // the frame's folder is gone: its write fails on the writer's thread
  EXPECT_EQ(frames.write(solver), "frames/particles_000000.vtu");
  try {
    frames.complete(solver);
    FAIL() << "the failed write was not reported";
  } catch (const Error& e) {
    EXPECT_EQ(e.kind(), Error::Kind::Io);
    EXPECT_NE(std::string(e.what()).find("particles_000000.vtu"), std::string::npos) << e.what();
  }
  EXPECT_FALSE(fs::exists(dir / "particles.pvd"));  // the .pvd never listed the frame
  frames.complete(solver);  // reported once: the series can go on (or be written after a fix)
}

/// The particles of `P` this rank holds: ids i with i % ranks == rank, none on rank 1 of three or
/// more (a rank may be empty).
ParticleStore share_of(const ParticleStore& P, const Comm& comm) {
  ParticleStore mine;
  if (comm.size() >= 3 && comm.rank() == 1) return mine;
  for (std::size_t p = 0; p < P.size(); ++p) {
    if (P.id[p] % comm.size() != comm.rank()) continue;
    const Vec3 x(P.x[0][p], P.x[1][p], P.x[2][p]), v(P.v[0][p], P.v[1][p], P.v[2][p]);
    const std::size_t i = mine.add(P.id[p], x, v, P.mass[p], P.volume[p], P.body[p]);
    for (int c = 0; c < 6; ++c) {
      mine.stress[c][i] = P.stress[c][p];
      mine.strain[c][i] = P.strain[c][p];
    }
  }
  return mine;
}

// Under ctest this is one rank (the frame is a .vtu); started as
//   mpirun -np 3 build/talus_io_tests --gtest_filter=FrameSeries.EveryRanksParticlesReadBackAsOneFrame
// it checks the distributed path: one piece per rank (rank 1 empty), rank 0's .pvtu and .pvd.
TEST(FrameSeries, EveryRanksParticlesReadBackAsOneFrame) {
  int argc = 0;
  char** argv = nullptr;
  MpiSession mpi(argc, argv);
  const Comm comm = Comm::world();
  // One folder for all ranks, rank 0's: made and removed by rank 0 alone.
  std::optional<ScratchDir> scratch;
  if (comm.root()) scratch.emplace("test_ranks_frame");
  const fs::path dir = comm.broadcast(scratch ? (*scratch / "out").string() : std::string());
  Solver solver(test::tumbling_block_scene(0.01));
  for (int s = 0; s < 3; ++s) solver.step();
  const ParticleStore all = solver.particles();
  solver.edit_particles() = share_of(all, comm);
  std::set<std::int64_t> expected_ids;
  for (std::int64_t id : all.id)
    if (!(comm.size() >= 3 && id % comm.size() == 1)) expected_ids.insert(id);

  prepare_output_folder(dir, nullptr, comm);
  RunProgress progress;
  FrameSeries frames(dir, false, progress, comm);
  const std::string name = frames.write(solver);
  frames.complete(solver);  // collective: every piece on disk, then rank 0's summary and .pvd
  comm.barrier();
  EXPECT_EQ(name, frame_name(0, comm.distributed()));
  const std::vector<std::int64_t> counts = comm.allgather(static_cast<std::int64_t>(solver.particles().size()));
  if (comm.root()) {
    vtkSmartPointer<vtkUnstructuredGrid> grid;
    if (comm.distributed()) {
      std::vector<std::string> pieces;
      for (int r = 0; r < comm.size(); ++r) {
        EXPECT_TRUE(fs::exists(dir / frame_piece_name(0, r))) << r;
        pieces.push_back(fs::path(frame_piece_name(0, r)).filename().string());
      }
      std::vector<std::string> sources;
      for (const auto& piece : test::xml_elements(test::file_bytes(dir / name), "Piece"))
        sources.push_back(piece.at("Source"));
      EXPECT_EQ(sources, pieces);
      EXPECT_FALSE(fs::exists(dir / frame_name(0)));
      vtkNew<vtkXMLPUnstructuredGridReader> reader;
      reader->SetFileName((dir / name).string().c_str());
      reader->Update();
      grid = reader->GetOutput();
    } else {
      vtkNew<vtkXMLUnstructuredGridReader> reader;
      reader->SetFileName((dir / name).string().c_str());
      reader->Update();
      grid = reader->GetOutput();
    }
    std::int64_t total = 0;
    for (std::int64_t c : counts) total += c;
    EXPECT_EQ(static_cast<std::size_t>(total), expected_ids.size());
    ASSERT_EQ(grid->GetNumberOfPoints(), total);
    std::set<std::int64_t> ids;
    vtkDataArray* id = grid->GetPointData()->GetArray("id");
    ASSERT_NE(id, nullptr);
    for (vtkIdType p = 0; p < grid->GetNumberOfPoints(); ++p) ids.insert(static_cast<std::int64_t>(id->GetTuple1(p)));
    EXPECT_EQ(ids, expected_ids);
    EXPECT_EQ(pvd_files(frames.pvd_path()), std::vector<std::string>{name});
  }
  comm.barrier();  // every rank is done reading before rank 0 removes the folder (`scratch`, as it goes)
}

}  // namespace
}  // namespace frame_series_test
}  // namespace talus
