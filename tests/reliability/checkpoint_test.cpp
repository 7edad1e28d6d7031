// Checkpoint/restart: a restored solver continues bit for bit; a checkpoint of another scene or
// another talus version, a missing or a corrupt file are refused with one line.
#include "../solver/scene_fixtures.hpp"
#include "reliability_fixtures.hpp"
#include "talus/core/error.hpp"
#include "talus/core/version.hpp"
#include "talus/io/checkpoint.hpp"
#include "talus/scene/scene_json.hpp"
#include "talus/solver/memory_estimate.hpp"
#include "talus/solver/solver.hpp"

#include <H5Cpp.h>
#include <gtest/gtest.h>

#include <algorithm>
#include <functional>
#include <limits>

#include <chrono>
#include <cstring>

namespace talus {
namespace checkpoint_test {
namespace {

/// Every array, bit for bit, and the solver's scalars.
void expect_identical(const Solver& a, const Solver& b) {
  ASSERT_EQ(a.particles().size(), b.particles().size());
  EXPECT_EQ(a.step_count(), b.step_count());
  const double ta = a.time(), tb = b.time();
  EXPECT_EQ(std::memcmp(&ta, &tb, sizeof(double)), 0);
  EXPECT_EQ(a.particles().id, b.particles().id);
  EXPECT_EQ(a.particles().body, b.particles().body);
  std::vector<const ParticleArray<double>*> arrays_b;
  b.particles().for_each_double_array([&](const char*, const ParticleArray<double>& v) { arrays_b.push_back(&v); });
  std::size_t i = 0, compared = 0;
  a.particles().for_each_double_array([&](const char* name, const ParticleArray<double>& v) {
    const ParticleArray<double>& w = *arrays_b[i++];
    ASSERT_EQ(v.size(), w.size()) << name;
    if (!v.empty()) ++compared;
    EXPECT_TRUE(v.empty() || std::memcmp(v.data(), w.data(), v.size() * sizeof(double)) == 0) << "array " << name << " differs";
  });
  EXPECT_GE(compared, 20u);
  const EnergyBudget ea = a.energies(), eb = b.energies();
  EXPECT_EQ(std::memcmp(&ea, &eb, sizeof(EnergyBudget)), 0);
  const EnergyGapTerms ga = a.energy_gap_terms(), gb = b.energy_gap_terms();
  EXPECT_EQ(std::memcmp(&ga, &gb, sizeof(EnergyGapTerms)), 0) << "energy gap terms";
}

Scene drucker_prager_scene() {
  return parse_scene(R"({
    "name": "dp_drop",
    "grid": { "origin": [0, 0, 0], "size": [0.6, 0.3, 0.4], "cell_size": 0.025 },
    "time": { "end": 0.2, "courant": 0.4 },
    "materials": { "sand": { "model": "drucker_prager", "density": 1600.0, "young": 2.0e6, "poisson": 0.3,
                             "friction_angle": 30.0, "cohesion": 5.0, "hardening_modulus": 2.0e4,
                             "kinematic_fraction": 0.2 } },
    "bodies": [ { "name": "heap", "material": "sand", "box": { "min": [0.1, 0.05, 0.0], "max": [0.3, 0.25, 0.25] },
                  "particles_per_cell": 2, "velocity": [1.5, 0.0, 0.0] } ],
    "boundaries": { "z-": { "type": "friction", "friction_coefficient": 0.5 }, "z+": "open" },
    "output": { "energy_gap_terms": true }
  })", "dp_drop");
}

void check_restart_is_bit_identical(const Scene& scene, int total, const std::vector<int>& splits) {
  const test::ScratchDir dir("rel_bitident");
  Solver reference(scene);
  for (int i = 0; i < total; ++i) reference.step();
  for (int k : splits) {
    SCOPED_TRACE("checkpoint after step " + std::to_string(k));
    Solver first(scene);
    for (int i = 0; i < k; ++i) first.step();
    const std::string path = (dir / "checkpoint.h5").string();
    write_checkpoint(path, first, RunProgress{});
    Solver resumed(scene);
    restore_checkpoint(resumed, read_checkpoint(path), path);
    EXPECT_EQ(resumed.step_count(), k);
    for (int i = k; i < total; ++i) resumed.step();
    expect_identical(reference, resumed);
    // Writing a checkpoint does not disturb the run that wrote it.
    for (int i = k; i < total; ++i) first.step();
    expect_identical(reference, first);
  }
}

/// The steps (counted from 0) of a `steps`-step run of the scene after which count(solver) grew.
template <class Count>
std::vector<int> steps_where_it_grew(const Scene& scene, int steps, Count count) {
  Solver probe(scene);
  std::vector<int> grew;
  for (int i = 0; i < steps; ++i) {
    const std::int64_t before = count(probe);
    probe.step();
    if (count(probe) > before) grew.push_back(i);
  }
  return grew;
}

// Two bodies tumbling onto a frictional floor: particles cross cells and blocks, so the runs sort
// both on drift and on the interval; the splits fall just after, between and just before sorts.
TEST(Checkpoint, RestartIsBitIdenticalToAnUninterruptedRun) {
  Scene scene = test::tumbling_block_scene(1.0);
  scene.sort_interval = 7;
  Solver probe(scene);
  for (int i = 0; i < 60; ++i) probe.step();
  EXPECT_GT(probe.sort_count(), 8);  // the split points really fall between sorts
  check_restart_is_bit_identical(scene, 60, {1, 7, 8, 19, 33, 59});
}

// MLS smoothing reuses a sort until the particles may have drifted a quarter cell
// (Solver::mls_needs_sort): the drift since the sort is part of the checkpoint, or a restart would
// sort at another step than the uninterrupted run and sum the P2G in another order.
TEST(Checkpoint, RestartIsBitIdenticalWithMlsSmoothing) {
  Scene scene = test::tumbling_block_scene(1.0);
  scene.smoothing.enabled = true;
  scene.sort_interval = 1000;  // only the drift and the slack sort
  const std::vector<int> sort_steps = steps_where_it_grew(scene, 60, [](const Solver& s) { return s.sort_count(); });
  ASSERT_GE(sort_steps.size(), 3u);  // the splits fall between sorts
  EXPECT_LT(sort_steps.size(), 30u);  // and the sort is reused between them
  check_restart_is_bit_identical(scene, 60, {sort_steps[1] + 1, sort_steps[2] - 1 > sort_steps[1] + 1 ? sort_steps[2] - 1 : 45});
}

// The `reused` MLS variant keeps the fits' weights between fits: they are in the checkpoint, or a
// restart would fit at another step than the uninterrupted run. The splits fall between fits.
TEST(Checkpoint, RestartIsBitIdenticalWithReusedMlsWeights) {
  Scene scene = test::tumbling_block_scene(1.0);
  scene.smoothing.enabled = true;
  scene.smoothing.mls.variant = MlsVariant::Reused;
  scene.smoothing.mls.reuse_strain = 0.05;
  const std::vector<int> fit_steps = steps_where_it_grew(scene, 60, [](const Solver& s) { return s.smoothing_fits(); });
  ASSERT_GE(fit_steps.size(), 3u);   // it fits again as the blocks strain
  ASSERT_LT(fit_steps.size(), 40u);  // and reuses the weights between fits
  int between = -1;
  for (std::size_t f = 1; f < fit_steps.size() && between < 0; ++f)
    if (fit_steps[f] > fit_steps[f - 1] + 2) between = fit_steps[f - 1] + 2;
  ASSERT_GT(between, 0);
  check_restart_is_bit_identical(scene, 60, {between, 37});
}

/// A plastic scene's restart after 80 steps is bit-identical, from checkpoints at steps 13 and 50;
/// the scene must have yielded by then, or the plastic state would not be exercised.
void check_plastic_restart(const Scene& scene) {
  Solver probe(scene);
  ASSERT_TRUE(probe.particles().has_plastic_state());
  for (int i = 0; i < 80; ++i) probe.step();
  double max_plastic = 0.0;
  for (double e : probe.particles().plastic_strain) max_plastic = std::max(max_plastic, e);
  EXPECT_GT(max_plastic, 0.0) << "the test should exercise the plastic state";
  check_restart_is_bit_identical(scene, 80, {13, 50});
}

TEST(Checkpoint, RestartIsBitIdenticalWithDruckerPragerState) { check_plastic_restart(drucker_prager_scene()); }

// μ(I) (docs/mu-i.md): the model's only state besides the stress is the accumulated plastic shear
// strain, and its strength depends on the step's dt; both come back from a checkpoint.
TEST(Checkpoint, RestartIsBitIdenticalWithMuIState) {
  const Scene scene = parse_scene(R"({
    "name": "mu_i_drop",
    "grid": { "origin": [0, 0, 0], "size": [0.6, 0.3, 0.4], "cell_size": 0.025 },
    "time": { "end": 0.2, "courant": 0.4 },
    "materials": { "beads": { "model": "mu_i", "density": 1500.0, "young": 2.0e6, "poisson": 0.3 } },
    "bodies": [ { "name": "heap", "material": "beads", "box": { "min": [0.1, 0.05, 0.0], "max": [0.3, 0.25, 0.25] },
                  "particles_per_cell": 2, "velocity": [1.5, 0.0, 0.0] } ],
    "boundaries": { "z-": { "type": "friction", "friction_coefficient": 0.5 }, "z+": "open" }
  })", "mu_i_drop");
  check_plastic_restart(scene);
}

// Periodic faces (docs/theory.md "Periodic boundaries"): a μ(I) layer flowing down a tilted gravity
// across the seams; the wraps' shift of the gravitational term is part of the checkpoint.
TEST(Checkpoint, RestartIsBitIdenticalWithPeriodicWraps) {
  const Scene scene = parse_scene(R"({
    "name": "periodic_flow",
    "grid": { "origin": [0, 0, 0], "size": [0.1, 0.05, 0.1], "cell_size": 0.0125 },
    "gravity": [4.0, 0.0, -8.96],
    "time": { "end": 0.2, "courant": 0.4 },
    "materials": { "beads": { "model": "mu_i", "density": 1500.0, "young": 2.0e5, "poisson": 0.3 } },
    "bodies": [ { "name": "layer", "material": "beads", "box": { "min": [0, 0, 0], "max": [0.1, 0.05, 0.05] },
                  "particles_per_cell": 2, "velocity": [2.0, 0.5, 0.0] } ],
    "boundaries": { "x-": "periodic", "x+": "periodic", "y-": "periodic", "y+": "periodic", "z-": "fixed", "z+": "open" }
  })", "periodic_flow");
  Solver probe(scene);
  for (int i = 0; i < 40; ++i) probe.step();
  // particles have wrapped by step 40: the gravitational term differs from -sum m g.x of the
  // wrapped positions by the shift the checkpoint must carry
  const ParticleStore& P = probe.particles();
  double wrapped_potential = 0.0;
  for (std::size_t p = 0; p < P.size(); ++p) wrapped_potential -= P.mass[p] * (4.0 * P.x[0][p] - 8.96 * P.x[2][p]);
  EXPECT_GT(std::abs(probe.energies().gravity - wrapped_potential), 1e-3 * std::abs(wrapped_potential));
  check_restart_is_bit_identical(scene, 60, {17, 40});
}

TEST(Checkpoint, RecordsVersionSceneHashAndEveryParticleArray) {
  const test::ScratchDir dir("rel_layout");
  Solver solver(drucker_prager_scene());
  for (int i = 0; i < 3; ++i) solver.step();
  const std::string path = (dir / "c.h5").string();
  RunProgress run;
  run.frame_times = {0.0, 0.01};
  run.frame_steps = {0, 2};
  run.next_frame = 0.02;
  write_checkpoint(path, solver, run);
  EXPECT_FALSE(test::fs::exists(path + ".tmp"));
  const Checkpoint c = read_checkpoint(path);
  EXPECT_EQ(c.talus_version, std::string(kVersion));
  EXPECT_EQ(c.scene_hash, scene_hash(solver.scene()));
  EXPECT_EQ(c.scene_hash.size(), 16u);
  EXPECT_EQ(c.solver.step, 3);
  EXPECT_EQ(c.run.frame_steps, run.frame_steps);
  EXPECT_EQ(c.run.next_frame, 0.02);
  std::size_t allocated = 0;
  solver.particles().for_each_double_array([&](const char* name, const ParticleArray<double>& v) {
    if (v.empty()) return;
    ++allocated;
    ASSERT_TRUE(c.double_arrays.count(name)) << name;
    EXPECT_TRUE(std::ranges::equal(c.double_arrays.at(name), v)) << name;
  });
  EXPECT_EQ(c.double_arrays.size(), allocated);
  EXPECT_TRUE(c.double_arrays.count("plastic_strain"));
  EXPECT_TRUE(std::ranges::equal(c.id, solver.particles().id));
}

// The cost of a checkpoint of the shipped default scene (reported in docs/reliability.md).
// scene.json shows grid.size rounded (0.6 for 48 cells of 0.0125, not cells x h = 0.6000000000000001)
// and still parses to a scene with the same hash: a checkpoint of an earlier build, whose hash is of
// the unrounded text, restarts from it.
TEST(Checkpoint, TheSceneFileShowsRoundedSizesWithTheSameHash) {
  const std::string text = test::small_slide_json(0.1, 0.02);
  Scene scene = parse_scene(text, "slide");
  scene.grid.h = 0.0125;
  scene.grid.cells = {48, 32, 32};
  ASSERT_NE(scene.grid.cells[0] * scene.grid.h, 0.6);  // the noise the rounding takes out
  const nlohmann::json shown = scene_file_json(scene);
  EXPECT_EQ(shown.at("grid").at("size")[0].get<double>(), 0.6);
  EXPECT_EQ(shown.at("grid").at("size")[1].get<double>(), 0.4);
  EXPECT_NE(shown.dump(2).find("\"size\": [\n      0.6,\n"), std::string::npos) << shown.dump(2);
  const Scene back = parse_scene(shown.dump(2), "scene.json");
  EXPECT_EQ(back.grid.cells, scene.grid.cells);
  EXPECT_EQ(scene_hash(back), scene_hash(scene));
  EXPECT_EQ(scene_to_json(back).dump(), scene_to_json(scene).dump());
}

TEST(Checkpoint, TheSceneFileNamesTheDefaultTensionCutoffWithTheSameHash) {
  const Scene scene = read_scene_file(std::string(TALUS_SOURCE_DIR) + "/inputs/denlinger_flume.json");
  const nlohmann::json shown = scene_file_json(scene);
  EXPECT_EQ(shown.at("materials").at("sand").at("tension_cutoff"), "apex");
  EXPECT_FALSE(scene_to_json(scene).at("materials").at("sand").contains("tension_cutoff"));  // the hashed text
  const Scene back = parse_scene(shown.dump(2), "scene.json");
  EXPECT_EQ(scene_hash(back), scene_hash(scene));
  EXPECT_EQ(scene_to_json(back).dump(), scene_to_json(scene).dump());
}

TEST(Checkpoint, DefaultSceneSizeAndWriteTime) {
  const test::ScratchDir dir("rel_size");
  Solver solver(read_scene_file(std::string(TALUS_SOURCE_DIR) + "/inputs/elastic_block_slide.json"));
  solver.step();
  const std::string path = (dir / "checkpoint.h5").string();
  const auto t0 = std::chrono::steady_clock::now();
  write_checkpoint(path, solver, RunProgress{});
  const double write_ms = std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count();
  const auto t1 = std::chrono::steady_clock::now();
  const Checkpoint c = read_checkpoint(path);
  const double read_ms = std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t1).count();
  const auto bytes = test::fs::file_size(path);
  std::printf("checkpoint of the default scene: %zu particles, %.2f MB, write %.1f ms, read %.1f ms\n",
              solver.particles().size(), bytes / 1e6, write_ms, read_ms);
  // The arrays dominate: no more than 10% overhead over the raw data.
  const double raw = solver.particles().size() * (8.0 * (c.double_arrays.size() + 1) + 2 + 12);
  EXPECT_LT(bytes, 1.1 * raw + 64 * 1024);
}

// The disk estimate counts a checkpoint as checkpoint_bytes_per_particle a particle (`talus check`'s
// "disk" line): the file holds that, with a few kB of scene and attributes, for a plastic state with
// its back stress, with and without cpGIMP's domains, and for an elastic scene.
TEST(Checkpoint, SizePerParticleIsWhatTheDiskEstimateCounts) {
  const test::ScratchDir dir("rel_estimate");
  Scene cpgimp = drucker_prager_scene();
  cpgimp.shape = ShapeKind::CpGimp;
  const Scene elastic = read_scene_file(std::string(TALUS_SOURCE_DIR) + "/inputs/elastic_block_slide.json");
  for (const Scene& scene : {drucker_prager_scene(), cpgimp, elastic}) {
    Solver solver(scene);
    solver.step();
    const std::string path = (dir / "checkpoint.h5").string();
    write_checkpoint(path, solver, RunProgress{});
    const double bytes = double(test::fs::file_size(path));
    const double estimate = double(solver.particles().size() * checkpoint_bytes_per_particle(scene));
    EXPECT_GE(bytes, estimate) << scene.name << " " << to_string(scene.shape);
    EXPECT_LE(bytes, estimate + 32 * 1024) << scene.name << " " << to_string(scene.shape);
  }
}

Error::Kind restore_error(const Scene& scene, const std::string& path, std::string* message) {
  try {
    Solver s(scene);
    restore_checkpoint(s, read_checkpoint(path), path);
  } catch (const Error& e) {
    *message = e.what();
    return e.kind();
  }
  *message = "no error";
  return Error::Kind::Io;
}

TEST(Checkpoint, RefusesAnotherSceneAnotherVersionAndBadFiles) {
  const test::ScratchDir dir("rel_refuse");
  const Scene scene = test::tumbling_block_scene(0.05);
  Solver solver(scene);
  solver.step();
  const std::string path = (dir / "c.h5").string();
  write_checkpoint(path, solver, RunProgress{});
  std::string msg;

  Scene other = scene;
  other.gravity = Vec3(0.0, 0.0, -9.0);
  other.end_time = 0.06;  // (a key a restart may change: not the one named)
  EXPECT_EQ(restore_error(other, path, &msg), Error::Kind::Input);
  EXPECT_NE(msg.find("belongs to another scene"), std::string::npos) << msg;
  // the two values, which "/time/end (differs)" did not give
  EXPECT_NE(msg.find("first difference at /gravity/2: checkpoint -9.81, this scene -9"), std::string::npos) << msg;
  EXPECT_EQ(msg.find('\n'), std::string::npos);
  // a long value is cut short, on the same line (a body's name: a restart may change the description)
  other = scene;
  other.bodies[0].name = std::string(200, 'a') + "\nb";
  EXPECT_EQ(restore_error(other, path, &msg), Error::Kind::Input);
  EXPECT_NE(msg.find("/bodies/0/name: checkpoint \"" + scene.bodies[0].name + "\", this scene \"" + std::string(36, 'a') + "..."),
            std::string::npos) << msg;
  EXPECT_EQ(msg.find(std::string(37, 'a')), std::string::npos) << msg;
  EXPECT_EQ(msg.find('\n'), std::string::npos);

  EXPECT_EQ(restore_error(scene, (dir / "missing.h5").string(), &msg), Error::Kind::Input);
  EXPECT_NE(msg.find("cannot open checkpoint " + (dir / "missing.h5").string() + ": no such file"), std::string::npos) << msg;
  EXPECT_EQ(restore_error(scene, dir.path().string(), &msg), Error::Kind::Input);
  EXPECT_NE(msg.find(": it is a folder, not a file"), std::string::npos) << msg;

  // (said "is not readable: H5Fopen failed")
  std::ofstream((dir / "junk.h5").string()) << "not hdf5 at all";
  EXPECT_EQ(restore_error(scene, (dir / "junk.h5").string(), &msg), Error::Kind::Input);
  EXPECT_NE(msg.find("checkpoint " + (dir / "junk.h5").string() + " is not an HDF5 file"), std::string::npos) << msg;

  {  // the same file, claiming another talus version
    H5::H5File file(path, H5F_ACC_RDWR);
    file.removeAttr("talus_version");
    H5::StrType type(H5::PredType::C_S1, 5);
    file.createAttribute("talus_version", type, H5::DataSpace(H5S_SCALAR)).write(type, "0.0.0");
  }
  EXPECT_EQ(restore_error(scene, path, &msg), Error::Kind::Input);
  EXPECT_NE(msg.find("written by talus 0.0.0"), std::string::npos) << msg;
}

// The keys a restart may change (time.end, time.courant, time.max_steps, guards.*) steer how the run
// goes on, not the state it goes on from: an instability's last good state resumed with a smaller
// time step (refused before 2026-12-07: "first difference at /time/courant"), a finished run
// extended. The restore takes them, restart_changes names each, and a time.end before the
// checkpoint's time is refused.
TEST(Checkpoint, ARestartMayChangeTheEndTheTimeStepAndTheGuards) {
  const test::ScratchDir dir("rel_changes");
  const Scene scene = test::tumbling_block_scene(0.05);
  Solver solver(scene);
  solver.step();
  solver.step();
  const std::string path = (dir / "c.h5").string();
  write_checkpoint(path, solver, RunProgress{});
  const Checkpoint checkpoint = read_checkpoint(path);
  EXPECT_TRUE(restart_changes(checkpoint, scene).empty());

  Scene changed = scene;
  changed.end_time = 0.08;
  changed.courant = 0.5 * scene.courant;
  changed.max_steps = 1000;
  changed.guards.energy_warning_factor = 0.2;
  Solver resumed(changed);
  ASSERT_NO_THROW(restore_checkpoint(resumed, checkpoint, path));
  EXPECT_EQ(resumed.step_count(), solver.step_count());
  EXPECT_EQ(resumed.time(), solver.time());
  EXPECT_EQ(resumed.particles().x[0], solver.particles().x[0]);
  const std::vector<std::string> lines = restart_changes(checkpoint, changed);
  ASSERT_EQ(lines.size(), 4u);
  EXPECT_EQ(lines[0], "guards.energy_warning_factor: 0.1 in the checkpoint's scene, 0.2 here");
  EXPECT_EQ(lines[1], fmt::format("time.courant: {} in the checkpoint's scene, {} here", scene.courant, changed.courant));
  EXPECT_EQ(lines[2], "time.end: 0.05 in the checkpoint's scene, 0.08 here");
  EXPECT_EQ(lines[3], "time.max_steps: 0 in the checkpoint's scene, 1000 here");
  // The next step takes the new Courant number's time step (the state is the checkpoint's).
  resumed.step();
  solver.step();
  EXPECT_NEAR(resumed.time() - checkpoint.solver.time, 0.5 * (solver.time() - checkpoint.solver.time),
              1e-9 * solver.time());

  Scene too_early = scene;
  too_early.end_time = 0.5 * checkpoint.solver.time;
  std::string msg;
  EXPECT_EQ(restore_error(too_early, path, &msg), Error::Kind::Input);
  EXPECT_NE(msg.find("time.end = "), std::string::npos) << msg;
  EXPECT_NE(msg.find("is before the checkpoint's time"), std::string::npos) << msg;
  Scene too_few = scene;
  too_few.max_steps = 1;  // the checkpoint is after step 2
  EXPECT_EQ(restore_error(too_few, path, &msg), Error::Kind::Input);
  EXPECT_NE(msg.find("time.max_steps = 1 is below the checkpoint's step, 2"), std::string::npos) << msg;
}

// How often checkpoints are written, and the scene's notes, may change too: a completed run without
// periodic checkpoints could not be extended later, since the interval it needed was a change refused.
TEST(Checkpoint, ARestartMayChangeTheCheckpointIntervalAndTheDescription) {
  const test::ScratchDir dir("rel_interval");
  const Scene scene = test::tumbling_block_scene(0.05);
  Solver solver(scene);
  solver.step();
  const std::string path = (dir / "c.h5").string();
  write_checkpoint(path, solver, RunProgress{});
  const Checkpoint checkpoint = read_checkpoint(path);
  Scene changed = scene;
  changed.output.checkpoint_interval = 0.01;
  changed.description = "extended";
  Solver resumed(changed);
  ASSERT_NO_THROW(restore_checkpoint(resumed, checkpoint, path));
  const std::vector<std::string> lines = restart_changes(checkpoint, changed);
  ASSERT_EQ(lines.size(), 2u);
  EXPECT_EQ(lines[0], "description: \"\" in the checkpoint's scene, \"extended\" here");
  EXPECT_EQ(lines[1], "output.checkpoint_interval: 0 in the checkpoint's scene, 0.01 here");
}

// A damaged or edited scalar is refused in one line: a time of NaN stepped forever without writing
// anything; a schedule time of NaN wrote no frame; a NaN velocity stopped the first step, which kept
// it as the last good state. A dataset whose header claims more values than the file holds is
// refused before they are allocated (2e9 asked for 16 GB).
TEST(Checkpoint, RefusesScalarsAndLengthsNoRunCouldHaveWritten) {
  const test::ScratchDir dir("rel_scalars");
  const Scene scene = test::tumbling_block_scene(0.05);
  Solver solver(scene);
  solver.step();
  const std::string good = (dir / "good.h5").string();
  write_checkpoint(good, solver, RunProgress{});
  const auto edited = [&](const std::string& name, const std::function<void(H5::H5File&)>& edit) {
    const std::string path = (dir / (name + ".h5")).string();
    test::fs::copy_file(good, path);
    H5::H5File file(path, H5F_ACC_RDWR);
    edit(file);
    return path;
  };
  const auto set_double = [](const char* group, const char* name, double value) {
    return [=](H5::H5File& f) { f.openGroup(group).openAttribute(name).write(H5::PredType::NATIVE_DOUBLE, &value); };
  };
  const double nan = std::numeric_limits<double>::quiet_NaN();
  const std::pair<std::string, std::string> cases[] = {
      {edited("time", set_double("/solver", "time", nan)), "its time is nan s"},
      {edited("dt", set_double("/solver", "last_dt", -1.0)), "its last time step is -1 s"},
      {edited("frame", set_double("/run", "next_frame", nan)), "/run next_frame is nan"},
      {edited("velocity", [&](H5::H5File& f) {
         H5::DataSet v = f.openGroup("/particles").openDataSet("v0");
         std::vector<double> values(solver.particles().size(), 0.0);
         values[3] = nan;
         v.write(values.data(), H5::PredType::NATIVE_DOUBLE);
       }), "'s v0 is nan"},
      {edited("huge", [](H5::H5File& f) {
         H5::Group p = f.openGroup("/particles");
         const hsize_t n = 2000000000;
         p.unlink("x0");
         H5::DataSpace space(1, &n);
         H5::DSetCreatPropList chunked;
         const hsize_t chunk = 1024;
         chunked.setChunk(1, &chunk);  // (a chunked dataset of 2e9 values takes no room until written)
         p.createDataSet("x0", H5::PredType::NATIVE_DOUBLE, space, chunked);
       }), "dataset x0 claims 2000000000 values, more than its"},
  };
  for (const auto& [path, expected] : cases) {
    std::string msg;
    restore_error(scene, path, &msg);
    EXPECT_NE(msg.find(expected), std::string::npos) << path << ": " << msg;
    EXPECT_EQ(msg.find('\n'), std::string::npos);
  }
}

// An edited or damaged checkpoint whose particles no step could have left is refused in one line
// (a position beyond the grid crashed the sort), before the run writes anything.
TEST(Checkpoint, RefusesParticlesNoStepCouldHaveLeft) {
  const test::ScratchDir dir("rel_damaged");
  const Scene scene = test::tumbling_block_scene(0.05);
  Solver solver(scene);
  solver.step();
  const std::string path = (dir / "c.h5").string();
  write_checkpoint(path, solver, RunProgress{});
  auto refusal = [&](const std::function<void(Checkpoint&)>& damage) {
    Checkpoint c = read_checkpoint(path);
    damage(c);
    Solver s(scene);
    try {
      restore_checkpoint(s, c, path);
    } catch (const Error& e) {
      EXPECT_EQ(e.exit_code(), 2) << e.what();
      return std::string(e.what());
    }
    return std::string("no error");
  };
  for (double x : {5.0, -0.5, std::nan("")})
    EXPECT_NE(refusal([x](Checkpoint& c) { c.double_arrays.at("x0")[3] = x; }).find("lies at"), std::string::npos);
  EXPECT_NE(refusal([](Checkpoint& c) { c.double_arrays.at("mass")[3] = -1.0; }).find("mass -1 kg"), std::string::npos);
  EXPECT_NE(refusal([](Checkpoint& c) { c.id[3] = c.id[4]; }).find("is saved twice"), std::string::npos);
  EXPECT_NE(refusal([](Checkpoint& c) { c.solver.sort_cell[0][3] = 100000; }).find("saved sort cell"), std::string::npos);
  EXPECT_EQ(refusal([](Checkpoint&) {}), "no error");
}

}  // namespace
}  // namespace checkpoint_test
}  // namespace talus
