// Distributed runs (docs/architecture.md "Distributed runs"): this binary runs under mpirun with 1, 2
// and 3 ranks (ctest Mpi.Ranks1..3). Every check is made on values that every rank holds alike
// (sums over the ranks, gathered particles broadcast by id), so that a failing check fails on all
// ranks together and no rank is left waiting in a collective.
#include "../support/scratch_dir.hpp"
#include "talus/core/comm.hpp"
#include "talus/driver/run_driver.hpp"
#include "talus/io/checkpoint.hpp"
#include "talus/particles/particle_migration.hpp"
#include "talus/scene/scene_json.hpp"
#include "talus/solver/solver.hpp"

#include <fmt/core.h>
#include <gtest/gtest.h>
#include <omp.h>
#include <vtkFieldData.h>
#include <vtkPointData.h>
#include <vtkStringArray.h>
#include <vtkSmartPointer.h>
#include <vtkUnstructuredGrid.h>
#include <vtkXMLPUnstructuredGridReader.h>

#include <algorithm>
#include <cmath>
#include <cstring>
#include <filesystem>
#include <map>
#include <numeric>
#include <optional>

namespace talus {
namespace {

const Comm& world() {
  static const Comm comm = Comm::world();
  return comm;
}

// Two elastic blocks flying at each other along x over a slip floor, no gravity along x: particles
// cross every slab boundary, in both directions, and the blocks collide (contact through the grid).
Scene crossing_blocks(double end_time, const char* scheme = "musl", const char* shape = "linear") {
  return parse_scene(fmt::format(R"({{
    "name": "crossing_blocks",
    "grid": {{ "origin": [0, 0, 0], "size": [0.64, 0.04, 0.08], "cell_size": 0.01 }},
    "gravity": [0, 0, -9.81],
    "time": {{ "end": {}, "courant": 0.4 }},
    "solver": {{ "scheme": "{}", "shape": "{}" }},
    "materials": {{ "rubber": {{ "model": "linear_elastic", "density": 1000, "young": 2e5, "poisson": 0.3 }},
                    "sand": {{ "model": "drucker_prager", "density": 1600, "young": 2e5, "poisson": 0.3,
                              "friction_angle": 30, "dilatancy_angle": 0, "cohesion": 50 }} }},
    "bodies": [
      {{ "name": "left", "material": "rubber", "box": {{ "min": [0.06, 0, 0], "max": [0.22, 0.04, 0.06] }},
         "particles_per_cell": 2, "velocity": [1.5, 0, 0] }},
      {{ "name": "right", "material": "sand", "box": {{ "min": [0.40, 0, 0], "max": [0.56, 0.04, 0.05] }},
         "particles_per_cell": 2, "velocity": [-1.5, 0, 0] }}
    ],
    "boundaries": {{ "x-": "slip", "x+": "slip", "y-": "slip", "y+": "slip",
                    "z-": {{ "type": "friction", "friction_coefficient": 0.3 }}, "z+": "open" }}
  }})",
                                 end_time, scheme, shape),
                     "crossing_blocks");
}

// Two blocks passing each other along x in two lanes (y) far enough apart that no node is shared:
// wherever a slab boundary lies, both blocks cross it, one up and one down.
Scene passing_blocks(double end_time) {
  return parse_scene(fmt::format(R"({{
    "name": "passing_blocks",
    "grid": {{ "origin": [0, 0, 0], "size": [0.64, 0.10, 0.08], "cell_size": 0.01 }},
    "gravity": [0, 0, -9.81],
    "time": {{ "end": {}, "courant": 0.4 }},
    "materials": {{ "rubber": {{ "model": "linear_elastic", "density": 1000, "young": 2e5, "poisson": 0.3 }} }},
    "bodies": [
      {{ "name": "eastbound", "material": "rubber", "box": {{ "min": [0.04, 0, 0], "max": [0.20, 0.03, 0.04] }},
         "particles_per_cell": 2, "velocity": [3, 0, 0] }},
      {{ "name": "westbound", "material": "rubber", "box": {{ "min": [0.44, 0.07, 0], "max": [0.60, 0.10, 0.04] }},
         "particles_per_cell": 2, "velocity": [-3, 0, 0] }}
    ],
    "boundaries": {{ "x-": "slip", "x+": "slip", "y-": "slip", "y+": "slip", "z-": "slip", "z+": "open" }}
  }})",
                                 end_time),
                     "passing_blocks");
}

// One block sliding along x on a slip floor: the mass travels through the slabs, so the slab bounds
// must follow it.
Scene sliding_block(double end_time) {
  return parse_scene(fmt::format(R"({{
    "name": "sliding_block",
    "grid": {{ "origin": [0, 0, 0], "size": [0.96, 0.04, 0.08], "cell_size": 0.01 }},
    "gravity": [0, 0, -9.81],
    "time": {{ "end": {} }},
    "materials": {{ "rubber": {{ "model": "linear_elastic", "density": 1000, "young": 2e5, "poisson": 0.3 }} }},
    "bodies": [ {{ "name": "block", "material": "rubber", "box": {{ "min": [0.04, 0, 0], "max": [0.28, 0.04, 0.04] }},
                  "particles_per_cell": 2, "velocity": [3.0, 0, 0] }} ],
    "boundaries": {{ "x-": "slip", "x+": "slip", "y-": "slip", "y+": "slip", "z-": "slip", "z+": "open" }}
  }})",
                                 end_time),
                     "sliding_block");
}

void run(Solver& s) {
  while (!s.finished()) s.step();
}

/// Every particle of a run, ordered by id, on every rank (gathered to rank 0, then broadcast).
struct State {
  std::vector<std::int64_t> id;
  std::array<std::vector<double>, 3> x, v;
  std::array<std::vector<double>, 6> stress;
  std::vector<double> mass;
};
std::vector<double> broadcast(const Comm& comm, const std::vector<double>& v) {
  std::string bytes(reinterpret_cast<const char*>(v.data()), v.size() * sizeof(double));
  bytes = comm.broadcast(bytes);
  std::vector<double> out(bytes.size() / sizeof(double));
  std::memcpy(out.data(), bytes.data(), bytes.size());
  return out;
}
State state_by_id(const Solver& s) {
  const ParticleStore all = gather_particles(s.comm(), s.particles());
  std::vector<std::size_t> order(all.size());
  std::iota(order.begin(), order.end(), 0);
  std::sort(order.begin(), order.end(), [&](std::size_t a, std::size_t b) { return all.id[a] < all.id[b]; });
  auto sorted = [&](const ParticleArray<double>& a) {
    std::vector<double> out(order.size());
    for (std::size_t i = 0; i < order.size(); ++i) out[i] = a[order[i]];
    return broadcast(s.comm(), out);
  };
  State st;
  std::vector<double> ids;
  for (std::size_t i : order) ids.push_back(static_cast<double>(all.id[i]));
  for (double d : broadcast(s.comm(), ids)) st.id.push_back(static_cast<std::int64_t>(d));
  for (int d = 0; d < 3; ++d) {
    st.x[d] = sorted(all.x[d]);
    st.v[d] = sorted(all.v[d]);
  }
  for (int c = 0; c < 6; ++c) st.stress[c] = sorted(all.stress[c]);
  st.mass = sorted(all.mass);
  return st;
}
bool same_bits(const std::vector<double>& a, const std::vector<double>& b) {
  return a.size() == b.size() && (a.empty() || std::memcmp(a.data(), b.data(), a.size() * sizeof(double)) == 0);
}
bool same_bits(const State& a, const State& b) {
  bool same = a.id == b.id && same_bits(a.mass, b.mass);
  for (int d = 0; d < 3; ++d) same = same && same_bits(a.x[d], b.x[d]) && same_bits(a.v[d], b.v[d]);
  for (int c = 0; c < 6; ++c) same = same && same_bits(a.stress[c], b.stress[c]);
  return same;
}
/// The largest |a - b| over positions [m] and over velocities [m/s] (same ids required).
std::pair<double, double> largest_difference(const State& a, const State& b) {
  double dx = 0.0, dv = 0.0;
  for (int d = 0; d < 3; ++d)
    for (std::size_t p = 0; p < a.id.size(); ++p) {
      dx = std::max(dx, std::abs(a.x[d][p] - b.x[d][p]));
      dv = std::max(dv, std::abs(a.v[d][p] - b.v[d][p]));
    }
  return {dx, dv};
}
double relative(double a, double b) { return std::abs(a - b) / std::max(std::abs(b), 1e-300); }

/// A folder every rank sees, fresh for the test, removed at the end: rank 0's scratch folder, named
/// for the test and the world's size.
struct SharedFolder {
  std::optional<test::ScratchDir> scratch;  // rank 0's alone: it makes and removes the folder
  std::filesystem::path path;
  explicit SharedFolder(const std::string& name) {
    if (world().root()) scratch.emplace(fmt::format("mpi_{}_{}", name, world().size()));
    path = world().broadcast(scratch ? scratch->path().string() : std::string());
  }
  ~SharedFolder() { world().barrier(); }  // every rank is done with it before rank 0's scratch goes
};

// Comm::exchange sends a buffer in pieces of at most piece_bytes (MPI's counts are ints: a message of
// more than 2 GB wrapped). Pieces of 7 bytes, buffers of 0 to 40 bytes (multiples of 7 among them),
// every rank to every rank including itself: what arrives is what was sent.
TEST(Distributed, ExchangeSendsBuffersInPieces) {
  const int size = world().size(), rank = world().rank();
  const auto buffer = [](int from, int to) {
    std::vector<unsigned char> b(static_cast<std::size_t>((7 * from + 5 * to) % 41));
    for (std::size_t k = 0; k < b.size(); ++k) b[k] = static_cast<unsigned char>(31 * from + 17 * to + k);
    return b;
  };
  std::vector<int> peers;
  std::vector<std::vector<unsigned char>> out;
  for (int r = 0; r < size; ++r) {
    peers.push_back(r);
    out.push_back(buffer(rank, r));
  }
  for (const std::int64_t piece : {std::int64_t(7), std::int64_t(1), Comm::kMaxMessageBytes}) {
    const auto in = world().exchange(peers, out, peers, piece);
    ASSERT_EQ(in.size(), peers.size());
    for (int r = 0; r < size; ++r) EXPECT_EQ(in[r], buffer(r, rank)) << "from " << r << ", pieces of " << piece;
  }
}

// The distributed run against the serial one of the same scene, which every rank also runs alone:
// the same particles, and mass, momentum, energies and positions equal to round-off.
TEST(Distributed, MatchesTheSerialRunToRoundOff) {
  for (const char* scheme : {"musl", "usf"}) {
    Scene scene = crossing_blocks(0.06, scheme, "cpgimp");
    scene.output.energy_gap_terms = true;  // a shared tile's grid terms counted once, as its wall work
    Solver serial(scene);
    run(serial);
    Solver distributed(scene, world());
    run(distributed);
    EXPECT_EQ(distributed.step_count(), serial.step_count()) << scheme;
    const State a = state_by_id(distributed), b = state_by_id(serial);
    ASSERT_EQ(a.id, b.id) << scheme;
    EXPECT_TRUE(same_bits(a.mass, b.mass)) << scheme;
    Vec3 pa = Vec3::Zero(), pb = Vec3::Zero();
    for (std::size_t p = 0; p < a.id.size(); ++p)
      for (int d = 0; d < 3; ++d) {
        pa[d] += a.mass[p] * a.v[d][p];
        pb[d] += b.mass[p] * b.v[d][p];
      }
    const auto [dx, dv] = largest_difference(a, b);
    const EnergyBudget ea = distributed.energies(), eb = serial.energies();
    const double de = relative(ea.total(), eb.total()), dk = relative(ea.kinetic, eb.kinetic);
    const double dp = (pa - pb).norm() / pb.norm();
    if (world().root())
      fmt::print("[{} ranks, {}] after {} steps: |dx| <= {:.2e} m, |dv| <= {:.2e} m/s, momentum {:.2e}, kinetic {:.2e}, "
                 "total energy {:.2e} (relative), friction work {:.6e} vs {:.6e} J\n",
                 world().size(), scheme, serial.step_count(), dx, dv, dp, dk, de, ea.friction_work, eb.friction_work);
    // Round-off: the node sums of the shared tiles are added in another order than on one rank.
    EXPECT_LT(dx, 1e-9) << scheme;
    EXPECT_LT(dp, 1e-9) << scheme;
    EXPECT_LT(de, 1e-9) << scheme;
    EXPECT_LT(relative(ea.friction_work, eb.friction_work), 1e-6) << scheme;  // counted once per tile
    EXPECT_LT(relative(ea.plastic_work, eb.plastic_work), 1e-6) << scheme;
    // the energy gap terms (docs/theory.md), each to round-off
    std::vector<std::string> names;
    std::vector<double> ga, gb;
    const EnergyGapTerms terms_a = distributed.energy_gap_terms(), terms_b = serial.energy_gap_terms();
    EnergyGapTerms::for_each_term(terms_a, [&](const char* name, double v) {
      names.push_back(name);
      ga.push_back(v);
    });
    EnergyGapTerms::for_each_term(terms_b, [&](const char*, double v) { gb.push_back(v); });
    for (std::size_t i = 0; i < ga.size(); ++i)
      EXPECT_LE(std::abs(ga[i] - gb[i]), 1e-6 * std::max(std::abs(gb[i]), 1e-9 * std::abs(eb.total()))) << scheme << " " << names[i];
  }
}

// Bit-identical from run to run and for any thread count per rank.
TEST(Distributed, SameBitsForAnyThreadCountAndRun) {
  const int saved = omp_get_max_threads();
  std::vector<State> states;
  std::vector<EnergyBudget> energies;
  for (int threads : {1, 2, 1}) {
    omp_set_num_threads(threads);
    Solver s(crossing_blocks(0.04), world());
    run(s);
    states.push_back(state_by_id(s));
    energies.push_back(s.energies());
  }
  omp_set_num_threads(saved);
  EXPECT_TRUE(same_bits(states[0], states[1])) << "1 and 2 threads a rank";
  EXPECT_TRUE(same_bits(states[0], states[2])) << "two runs on 1 thread";
  EXPECT_EQ(std::memcmp(&energies[0], &energies[1], sizeof(EnergyBudget)), 0);
}

// Particles cross the slab boundaries in both directions and every one is kept: the same ids, the
// same total mass.
TEST(Distributed, ParticlesCrossSlabsBothWays) {
  Solver s(passing_blocks(0.12), world());
  auto owners = [&] {  // id -> rank, on every rank
    std::vector<double> mine;
    for (std::int64_t id : s.particles().id) mine.push_back(static_cast<double>(id));
    std::vector<std::int64_t> counts;
    const std::vector<double> all = broadcast(world(), world().gather(mine, &counts));
    std::vector<double> count_list(counts.begin(), counts.end());
    const std::vector<double> per_rank = broadcast(world(), count_list);
    std::map<std::int64_t, int> owner;
    std::size_t at = 0;
    for (std::size_t r = 0; r < per_rank.size(); ++r)
      for (std::int64_t i = 0; i < static_cast<std::int64_t>(per_rank[r]); ++i) owner[static_cast<std::int64_t>(all[at++])] = static_cast<int>(r);
    return owner;
  };
  const std::map<std::int64_t, int> before = owners();
  const std::int64_t particles = s.distribution().particles;
  run(s);
  const std::map<std::int64_t, int> after = owners();
  ASSERT_EQ(after.size(), before.size());
  int up = 0, down = 0;
  for (const auto& [id, r] : before) {
    ASSERT_TRUE(after.count(id)) << "particle " << id << " lost";
    up += after.at(id) > r;
    down += after.at(id) < r;
  }
  const DistributionStats d = s.distribution();
  EXPECT_EQ(d.particles, particles);
  if (world().root())
    fmt::print("[{} ranks] {} particles moved to a higher rank, {} to a lower one; {} migrations, {} rebalances\n",
               world().size(), up, down, d.migrated, d.rebalances);
  if (world().distributed()) {
    EXPECT_GT(up, 0);
    EXPECT_GT(down, 0);
    EXPECT_GE(d.migrated, up + down);
  } else {
    EXPECT_EQ(up + down, 0);
  }
}

// The slab bounds follow a block that slides through them: the work stays balanced.
TEST(Distributed, SlabsFollowAMovingMass) {
  Solver s(sliding_block(0.15), world());
  const SlabDecomposition initial = s.decomposition();
  const double start_x = [&] {
    const State st = state_by_id(s);
    return std::accumulate(st.x[0].begin(), st.x[0].end(), 0.0) / st.x[0].size();
  }();
  run(s);
  const State st = state_by_id(s);
  const double end_x = std::accumulate(st.x[0].begin(), st.x[0].end(), 0.0) / st.x[0].size();
  // the particles per column now, and how the slabs of the start would share them
  std::vector<std::int64_t> work(initial.columns(), 0);
  for (double x : st.x[0]) ++work[initial.column_of_cell(s.scene().grid.cell_of(0, x))];
  const double unmoved = initial.imbalance(work), now = s.decomposition().imbalance(work);
  const DistributionStats d = s.distribution();
  if (world().root())
    fmt::print("[{} ranks] the block moved {:.3f} m; {} rebalances; imbalance at the end {:.3f} (the slabs of the start "
               "would have {:.3f}), at most {:.3f} during the run\n",
               world().size(), end_x - start_x, d.rebalances, now, unmoved, d.max_imbalance);
  EXPECT_GT(end_x - start_x, 0.3);  // more than the block's length: it leaves every slab of the start
  if (world().distributed()) {
    EXPECT_GT(d.rebalances, 0);
    EXPECT_GE(unmoved, 0.75 * world().size());  // static slabs would leave most ranks idle
    // the moving slabs keep it near balance (whole columns of 4 cells: a 24-cell block cannot be
    // cut into three equal parts of columns)
    EXPECT_LT(now, 1.5);
    EXPECT_LT(d.max_imbalance, 1.5);
  }
}

// A run's frames: each rank writes its piece, rank 0 a .pvtu that VTK reads as one data set.
TEST(Distributed, FramesReadBackAsOneDataSet) {
  SharedFolder folder("frames");
  Scene scene = crossing_blocks(0.02);
  scene.output.frame_interval = 0.01;
  Solver s(std::move(scene), world());
  RunOptions options;
  options.out_dir = folder.path;
  options.progress = false;
  const RunSummary summary = run_scene(s, options);
  const std::int64_t particles = s.distribution().particles;
  std::int64_t points = -1, unique_ids = -1;
  std::string body_names;
  if (world().root()) {
    const std::string last = (folder.path / fmt::format("frames/particles_{:06}.{}", summary.frames - 1,
                                                        world().distributed() ? "pvtu" : "vtu")).string();
    EXPECT_TRUE(std::filesystem::exists(last)) << last;
    if (world().distributed()) {
      auto reader = vtkSmartPointer<vtkXMLPUnstructuredGridReader>::New();
      reader->SetFileName(last.c_str());
      reader->Update();
      vtkUnstructuredGrid* grid = reader->GetOutput();
      points = grid->GetNumberOfPoints();
      std::vector<std::int64_t> ids;
      auto* id_array = grid->GetPointData()->GetArray("id");
      if (id_array)
        for (vtkIdType i = 0; i < id_array->GetNumberOfTuples(); ++i) ids.push_back(static_cast<std::int64_t>(id_array->GetTuple1(i)));
      std::sort(ids.begin(), ids.end());
      unique_ids = std::unique(ids.begin(), ids.end()) - ids.begin();
      // the bodies' names, which every piece carries in its field data, reach the data set
      if (auto* names = vtkStringArray::SafeDownCast(grid->GetFieldData()->GetAbstractArray("body_names")))
        for (vtkIdType i = 0; i < names->GetNumberOfValues(); ++i) body_names += std::string(names->GetValue(i)) + ";";
    } else {
      points = unique_ids = particles;
      body_names = "left;right;";
    }
  }
  const double read = world().broadcast(fmt::format("{} {}", points, unique_ids)) == fmt::format("{} {}", particles, particles);
  EXPECT_TRUE(read) << "the last frame holds every particle once";
  EXPECT_EQ(world().broadcast(body_names), "left;right;") << "the frame names the bodies";
}

// Particles leave through the open x- and x+ faces from the slabs at either end: the mass and count
// by face (run.json's end.outflow_by_face) are every rank's summed, the serial run's, and a restart
// on the same ranks keeps them bit for bit.
TEST(Distributed, OutflowByFaceIsSummedOverTheRanksAndCheckpointed) {
  SharedFolder folder("outflow_faces");
  Scene scene = crossing_blocks(0.05);
  scene.walls[0][0].type = scene.walls[0][1].type = WallType::Open;
  scene.bodies[0].velocity = Vec3(-3.0, 0, 0);  // apart, each out through its end
  scene.bodies[1].velocity = Vec3(3.0, 0, 0);
  Solver serial(scene);
  run(serial);
  const OutflowFaces expected = serial.outflow_faces();
  ASSERT_GT(expected.particles[0], 0);
  ASSERT_GT(expected.particles[1], 0);
  const std::string path = (folder.path / "checkpoint.h5").string();
  Solver whole(scene, world());
  while (whole.outflow_particles() == 0) whole.step();  // a checkpoint after some have left
  write_checkpoint(path, whole, RunProgress{});
  world().barrier();  // rank 0 has written it
  run(whole);
  const OutflowFaces all = whole.outflow_faces();
  EXPECT_EQ(all.particles, expected.particles);
  for (int face = 0; face < OutflowFaces::kFaces; ++face)
    EXPECT_LE(std::abs(all.mass[face] - expected.mass[face]), 1e-12 * serial.outflow_mass()) << OutflowFaces::kNames[face];
  EXPECT_EQ(all.particles[0] + all.particles[1], whole.outflow_particles());
  Solver same(scene, world());
  restore_checkpoint(same, read_checkpoint(path, world()), path);
  run(same);
  const OutflowFaces resumed = same.outflow_faces();
  EXPECT_EQ(resumed.particles, all.particles);
  EXPECT_EQ(std::memcmp(resumed.mass.data(), all.mass.data(), sizeof(all.mass)), 0);
}

// A restart on ranks whose slabs seed no particle (a body narrower than a block column, at the
// grid's low end): each rank took the scene's arrays from its own seeded ones, and one with none
// refused the checkpoint ("particle array mass is not used") alone while the others waited in the
// restore's first collective, forever. From a one-rank checkpoint and from one of these ranks.
TEST(Distributed, RestartWithSlabsThatSeedNothing) {
  SharedFolder folder("restart_empty_slabs");
  const Scene scene = parse_scene(R"({
    "name": "narrow_block",
    "grid": { "origin": [0, 0, 0], "size": [0.64, 0.04, 0.08], "cell_size": 0.01 },
    "time": { "end": 0.02, "courant": 0.4 },
    "materials": { "sand": { "model": "drucker_prager", "density": 1600, "young": 2e5, "poisson": 0.3,
                             "friction_angle": 30, "cohesion": 50 } },
    "bodies": [ { "name": "b", "material": "sand", "box": { "min": [0.0, 0, 0], "max": [0.02, 0.04, 0.04] },
                  "particles_per_cell": 2, "velocity": [1.0, 0, 0] } ],
    "boundaries": { "x+": "open", "z-": { "type": "friction", "friction_coefficient": 0.3 }, "z+": "open" }
  })", "narrow_block");
  const std::string serial_path = (folder.path / "serial.h5").string();
  const std::string path = (folder.path / "ranks.h5").string();
  Solver serial(scene);
  for (int i = 0; i < 10; ++i) serial.step();
  if (world().root()) write_checkpoint(serial_path, serial, RunProgress{});
  world().barrier();
  Solver from_serial(scene, world());
  ASSERT_NO_THROW(restore_checkpoint(from_serial, read_checkpoint(serial_path), serial_path));
  EXPECT_EQ(from_serial.step_count(), 10);
  write_checkpoint(path, from_serial, RunProgress{});
  world().barrier();
  Solver same(scene, world()), own_part(scene, world());
  ASSERT_NO_THROW(restore_checkpoint(same, read_checkpoint(path), path));
  ASSERT_NO_THROW(restore_checkpoint(own_part, read_checkpoint(path, world()), path));  // (some parts empty)
  run(from_serial);
  run(same);
  run(own_part);
  EXPECT_TRUE(same_bits(state_by_id(same), state_by_id(from_serial))) << "restart on the same ranks";
  EXPECT_TRUE(same_bits(state_by_id(own_part), state_by_id(from_serial))) << "each rank reading its own part";
}

// Restart: bit for bit on the same number of ranks; on one rank (every rank restarts the file
// alone) and from a one-rank checkpoint, to round-off.
TEST(Distributed, RestartOnAnyRankCount) {
  SharedFolder folder("restart");
  const Scene scene = crossing_blocks(0.05);
  const std::string path = (folder.path / "checkpoint.h5").string();
  const std::string serial_path = (folder.path / "serial.h5").string();
  // The uninterrupted run, and a checkpoint after 60 steps.
  Solver whole(scene, world());
  RunProgress progress;
  for (int i = 0; i < 60; ++i) whole.step();
  write_checkpoint(path, whole, progress);
  world().barrier();  // rank 0 has written it
  run(whole);
  const State reference = state_by_id(whole);
  const EnergyBudget reference_energy = whole.energies();

  // (each rank reads only its own saved particles: read_checkpoint with the ranks)
  Solver same(scene, world());
  restore_checkpoint(same, read_checkpoint(path, world()), path);
  EXPECT_EQ(same.step_count(), 60);
  run(same);
  EXPECT_TRUE(same_bits(state_by_id(same), reference)) << "restart on the same ranks";
  const EnergyBudget same_energy = same.energies();
  EXPECT_EQ(std::memcmp(&same_energy, &reference_energy, sizeof(EnergyBudget)), 0);

  // One rank from the distributed checkpoint: every rank runs it alone.
  Solver one(scene);
  restore_checkpoint(one, read_checkpoint(path), path);
  run(one);
  const State from_one = state_by_id(one);
  ASSERT_EQ(from_one.id, reference.id);
  const auto [dx1, dv1] = largest_difference(from_one, reference);
  EXPECT_LT(dx1, 1e-9);
  EXPECT_LT(relative(one.energies().total(), reference_energy.total()), 1e-9);

  // The distributed run from a one-rank checkpoint (rank 0 writes it).
  Solver serial(scene);
  for (int i = 0; i < 60; ++i) serial.step();
  if (world().root()) write_checkpoint(serial_path, serial, progress);
  world().barrier();
  Solver from_serial(scene, world());
  restore_checkpoint(from_serial, read_checkpoint(serial_path), serial_path);
  run(from_serial);
  const auto [dx2, dv2] = largest_difference(state_by_id(from_serial), reference);
  EXPECT_LT(dx2, 1e-9);
  if (world().root())
    fmt::print("[{} ranks] restart on 1 rank: |dx| <= {:.2e} m; 1-rank checkpoint on {} ranks: |dx| <= {:.2e} m\n",
               world().size(), dx1, world().size(), dx2);
}

}  // namespace
}  // namespace talus

// MPI around GoogleTest: every rank runs every test; rank 0 prints the results.
int main(int argc, char** argv) {
  talus::MpiSession mpi(argc, argv);
  ::testing::InitGoogleTest(&argc, argv);
  if (!talus::world().root()) {
    auto& listeners = ::testing::UnitTest::GetInstance()->listeners();
    delete listeners.Release(listeners.default_result_printer());
  }
  return RUN_ALL_TESTS();
}
