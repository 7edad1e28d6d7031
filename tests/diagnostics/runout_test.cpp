// Runout diagnostics on synthetic particle sets: quantile front and tail that stray particles do not
// move, centre of mass and its velocity along the bed, the deposit raster, the terrain's runout
// plane, and the files the run driver writes.
#include "../support/quiet_run.hpp"
#include "../support/scratch_dir.hpp"
#include "talus/core/error.hpp"
#include "talus/diagnostics/runout.hpp"
#include "talus/io/checkpoint.hpp"
#include "talus/driver/run_driver.hpp"
#include "talus/io/runout_output.hpp"
#include "talus/scene/scene_json.hpp"
#include "talus/solver/solver.hpp"

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>
#include <omp.h>
#include <unistd.h>
#include <vtkCellData.h>
#include <vtkNew.h>
#include <vtkPointData.h>
#include <vtkUnstructuredGrid.h>
#include <vtkXMLUnstructuredGridReader.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <numbers>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <numeric>
#include <random>
#include <sstream>

namespace talus {
namespace runout_test {
namespace {

namespace fs = std::filesystem;

/// n equal particles spread evenly over s in [0, length) (x = s on a flat bed), shuffled so the store
/// order is not the s order.
ParticleStore uniform_strip(int n, double length, double mass = 1.0, unsigned seed = 1) {
  std::vector<int> order(n);
  std::iota(order.begin(), order.end(), 0);
  std::mt19937 rng(seed);
  std::shuffle(order.begin(), order.end(), rng);
  ParticleStore P;
  for (int k : order) P.add(k, Vec3((k + 0.5) * length / n, 0.1 * (k % 3), 0.05), Vec3(1.0, 0.0, 0.0), mass, 1e-3, 0);
  return P;
}

// Once every particle has left through the open faces there is nothing to measure: the sample has
// no mass and no position, and the result is the last front measured, with the time all had left.
TEST(Runout, AfterEveryParticleHasLeftTheResultIsTheLastFrontMeasured) {
  RunoutSpec spec;
  spec.has_gate = true;
  spec.gate_x = 0.1;
  RunoutMonitor monitor(spec, FlumeCoordinates());
  monitor.sample(uniform_strip(1000, 2.0), 0.0, 0);
  const RunoutSample before = monitor.sample(uniform_strip(1000, 3.0), 0.5, 100);
  const RunoutSample none = monitor.sample(ParticleStore(), 0.6, 120);
  EXPECT_EQ(none.mass, 0.0);
  for (double v : {none.front, none.tail, none.s_min, none.s_max, none.centre_s, none.centre[0], none.centre_velocity_s,
                   none.front_velocity})
    EXPECT_TRUE(std::isnan(v)) << v;
  const RunoutResult r = monitor.result();
  ASSERT_TRUE(r.all_left_time.has_value());
  EXPECT_EQ(*r.all_left_time, 0.6);
  EXPECT_EQ(r.time, 0.5);
  EXPECT_EQ(r.front, before.front);
  EXPECT_EQ(r.tail, before.tail);
  EXPECT_EQ(r.from_gate, before.front - 0.1);
  const nlohmann::json j = nlohmann::json::parse(runout_result_json(r));
  EXPECT_EQ(j.at("time").get<double>(), 0.5);
  EXPECT_EQ(j.at("front").get<double>(), before.front);
  EXPECT_EQ(j.at("all_left_time").get<double>(), 0.6);
  // a history row of the empty sample reads back as one
  const std::optional<RunoutSample> row = parse_runout_csv_row(runout_csv_row(none));
  ASSERT_TRUE(row.has_value());
  EXPECT_TRUE(std::isnan(row->front));
  EXPECT_EQ(row->step, 120);
}

TEST(Runout, QuantileFrontAndTailOfAUniformStrip) {
  const ParticleStore P = uniform_strip(1000, 2.0);
  const RunoutSample r = measure_runout(P, FlumeCoordinates(), 0.995, 0.005);
  // The 995th of 1000 particles (cumulative mass 995 >= 0.995 * 1000) at s = 994.5 * 2 / 1000.
  EXPECT_DOUBLE_EQ(r.front, 994.5 * 0.002);
  EXPECT_DOUBLE_EQ(r.tail, 4.5 * 0.002);
  EXPECT_DOUBLE_EQ(r.s_max, 999.5 * 0.002);
  EXPECT_DOUBLE_EQ(r.mass, 1000.0);
  EXPECT_NEAR(r.centre_s, 1.0, 1e-12);
  EXPECT_NEAR(r.centre[0], 1.0, 1e-12);
  EXPECT_NEAR(r.centre[2], 0.05, 1e-12);
  EXPECT_NEAR(r.centre_velocity_s, 1.0, 1e-12);
}

TEST(Runout, StrayParticlesDoNotMoveTheFront) {
  ParticleStore P = uniform_strip(1000, 2.0);
  const RunoutSample clean = measure_runout(P, FlumeCoordinates(), 0.995, 0.005);
  // Three strays (0.3% of the mass) far ahead and two far behind.
  for (int k = 0; k < 3; ++k) P.add(2000 + k, Vec3(5.0 + k, 0.0, 0.05), Vec3::Zero(), 1.0, 1e-3, 0);
  for (int k = 0; k < 2; ++k) P.add(3000 + k, Vec3(-3.0 - k, 0.0, 0.05), Vec3::Zero(), 1.0, 1e-3, 0);
  const RunoutSample stray = measure_runout(P, FlumeCoordinates(), 0.995, 0.005);
  EXPECT_DOUBLE_EQ(stray.s_max, 7.0);   // the extremes see them ...
  EXPECT_DOUBLE_EQ(stray.s_min, -4.0);
  // ... the quantiles move by a few particle spacings (0.002 m), not metres. Exactly: 1005 particles,
  // 0.995 * 1005 = 999.975, so the front is the 1000th in s order = strip particle 997 (two strays
  // lie behind); 0.005 * 1005 = 5.025, so the tail is the 6th = strip particle 3.
  EXPECT_DOUBLE_EQ(stray.front, 997.5 * 0.002);
  EXPECT_DOUBLE_EQ(stray.tail, 3.5 * 0.002);
  EXPECT_NEAR(stray.front, clean.front, 3.01 * 0.002);
  EXPECT_NEAR(stray.tail, clean.tail, 1.01 * 0.002);
  // The raw extremes are not robust: that is why front and tail are quantiles.
  EXPECT_GT(stray.s_max - clean.s_max, 5.0);
}

TEST(Runout, IndependentOfStoreOrderAndThreadCount) {
  const ParticleStore a = uniform_strip(5000, 1.7, 0.3, 1);
  const ParticleStore b = uniform_strip(5000, 1.7, 0.3, 2);  // another order of the same particles
  omp_set_num_threads(1);
  const RunoutSample ra = measure_runout(a, FlumeCoordinates(), 0.99, 0.01);
  omp_set_num_threads(2);
  const RunoutSample rb = measure_runout(b, FlumeCoordinates(), 0.99, 0.01);
  EXPECT_EQ(ra.front, rb.front);
  EXPECT_EQ(ra.tail, rb.tail);
  EXPECT_EQ(ra.centre_s, rb.centre_s);  // bit for bit: summed in (s, id) order
  EXPECT_EQ(ra.centre[1], rb.centre[1]);
  EXPECT_EQ(measure_deposit(a, FlumeCoordinates(), 0, 2, -0.1, 0.3, 0.05).thickness,
            measure_deposit(b, FlumeCoordinates(), 0, 2, -0.1, 0.3, 0.05).thickness);
}

TerrainSpec flume_terrain(double slope_deg, double radius) {
  // A slope down to a horizontal runout plane at z = 0, the vertex at x = 1.
  const double t = std::tan(slope_deg * M_PI / 180.0);
  return TerrainSpec{{{0.0, t}, {1.0, 0.0}, {2.5, 0.0}}, {0.0, radius, 0.0}};
}

TEST(Runout, ArcLengthAndTangentVelocityOnATerrain) {
  const TerrainProfile profile(flume_terrain(31.4, 0.2));
  const FlumeCoordinates c(profile);
  // A particle on the slope moving down it at 2 m/s, one on the runout plane at rest.
  const double th = 31.4 * M_PI / 180.0;
  ParticleStore P;
  P.add(0, Vec3(0.3, 0.0, profile.height(0.3) + 0.01), Vec3(2 * std::cos(th), 0.0, -2 * std::sin(th)), 1.0, 1e-3, 0);
  P.add(1, Vec3(2.0, 0.0, 0.01), Vec3::Zero(), 1.0, 1e-3, 0);
  const RunoutSample r = measure_runout(P, c, 0.995, 0.005);
  EXPECT_NEAR(r.tail, 0.3 / std::cos(th), 1e-12);  // s on the straight slope
  EXPECT_NEAR(r.front, profile.arc_length(2.0), 1e-12);
  EXPECT_NEAR(r.centre_velocity_s, 1.0, 1e-12);  // (2 + 0) / 2 along the local tangents
}

TEST(Runout, RunoutPlaneStartsWhereTheTransitionEnds) {
  const double th = 31.4 * M_PI / 180.0, r = 0.2;
  const FlumeCoordinates c{TerrainProfile(flume_terrain(31.4, r))};
  const double x = *c.last_segment_start();
  EXPECT_NEAR(x, 1.0 + r * std::tan(th / 2), 1e-12);  // tangent length of the fillet
  // The bed is level from there on and still curved just before.
  EXPECT_NEAR(c.profile().slope(x + 1e-6), 0.0, 1e-12);
  EXPECT_LT(c.profile().slope(x - 1e-3), -1e-3);
  // A sharp kink: the vertex itself. Flat: unknown.
  EXPECT_DOUBLE_EQ(*FlumeCoordinates(TerrainProfile(flume_terrain(31.4, 0.0))).last_segment_start(), 1.0);
  EXPECT_FALSE(FlumeCoordinates().last_segment_start().has_value());
  // The default outside the grid along x is left out (a runout_plane_x there is refused): measured
  // from it, a grid cut short of the transition was "3.1 m short of the runout plane".
  RunoutSpec spec;
  spec.enabled = true;
  const auto plane_of = [&](RunoutGrid grid) {
    RunoutMonitor monitor(spec, c, grid);
    monitor.sample(uniform_strip(100, 0.8), 0.0, 0);
    return monitor.result().runout_plane_s;
  };
  ASSERT_TRUE(plane_of(RunoutGrid{0.0, 2.5, 0.05}).has_value());
  EXPECT_NEAR(*plane_of(RunoutGrid{0.0, 2.5, 0.05}), c.s(x), 1e-12);
  EXPECT_FALSE(plane_of(RunoutGrid{0.0, 1.0, 0.05}).has_value());
  EXPECT_FALSE(plane_of(RunoutGrid{100.0, 108.0, 0.05}).has_value());
  spec.has_runout_plane = true;  // given: as given
  spec.runout_plane_x = 0.5;
  EXPECT_NEAR(*plane_of(RunoutGrid{0.0, 1.0, 0.05}), c.s(0.5), 1e-12);
}

// runout.json gave the front and tail only as arc length s: it gives their x and, on a terrain, the
// bed's height z there too (null on a flat grid).
TEST(Runout, TheResultGivesWhereTheFrontAndTailLie) {
  RunoutSpec spec;
  spec.enabled = true;
  const FlumeCoordinates c{TerrainProfile(flume_terrain(31.4, 0.2))};
  RunoutMonitor monitor(spec, c);
  monitor.sample(uniform_strip(1000, 2.0), 0.0, 0);
  const RunoutResult r = monitor.result();
  EXPECT_NEAR(r.front_x, 994.5 * 0.002, 1e-9);  // the front particle's x (its s is the arc length there)
  EXPECT_NEAR(r.tail_x, 4.5 * 0.002, 1e-9);
  EXPECT_GT(r.front, r.front_x);  // s runs along the sloping bed: longer than x
  ASSERT_TRUE(r.front_z && r.tail_z);
  EXPECT_DOUBLE_EQ(*r.front_z, c.profile().height(r.front_x));
  EXPECT_DOUBLE_EQ(*r.tail_z, c.profile().height(r.tail_x));
  EXPECT_GT(*r.tail_z, *r.front_z);  // the tail lies upslope
  const nlohmann::json j = nlohmann::json::parse(runout_result_json(r));
  EXPECT_EQ(j.at("front_x").get<double>(), r.front_x);
  EXPECT_EQ(j.at("front_z").get<double>(), *r.front_z);
  EXPECT_EQ(j.at("tail_x").get<double>(), r.tail_x);
  EXPECT_EQ(j.at("tail_z").get<double>(), *r.tail_z);
  RunoutMonitor flat(spec, FlumeCoordinates());
  flat.sample(uniform_strip(1000, 2.0), 0.0, 0);
  const RunoutResult f = flat.result();
  EXPECT_EQ(f.front_x, f.front);
  const nlohmann::json jf = nlohmann::json::parse(runout_result_json(f));
  EXPECT_TRUE(jf.at("front_z").is_null());
  EXPECT_TRUE(jf.at("tail_z").is_null());
}

/// The first `n` comma-separated fields of a CSV line (a runout.csv row as an older talus wrote it).
std::string first_fields(const std::string& line, std::size_t n) {
  std::size_t end = 0;
  for (std::size_t field = 0; field < n && end != std::string::npos; ++field) end = line.find(',', end + (field > 0));
  return line.substr(0, end);
}

// runout.csv had no x or z of the front and tail, which runout.json gives: each row has them now, in
// four columns after the thirteen it had (front_x, front_z, tail_x, tail_z), nan z on a flat grid.
TEST(Runout, TheHistoryGivesWhereTheFrontAndTailLie) {
  RunoutSpec spec;
  spec.enabled = true;
  const FlumeCoordinates c{TerrainProfile(flume_terrain(31.4, 0.2))};
  RunoutMonitor monitor(spec, c);
  const RunoutSample s = monitor.sample(uniform_strip(1000, 2.0), 0.0, 0);
  const RunoutResult r = monitor.result();
  EXPECT_EQ(s.front_x, r.front_x);
  EXPECT_EQ(s.tail_x, r.tail_x);
  EXPECT_EQ(s.front_z, *r.front_z);
  EXPECT_EQ(s.tail_z, *r.tail_z);
  const std::string header = runout_csv_header();
  EXPECT_EQ(header.substr(header.find(",front_velocity,") + 1), "front_velocity,front_x,front_z,tail_x,tail_z");
  const std::string row = runout_csv_row(s);
  EXPECT_EQ(std::count(row.begin(), row.end(), ','), std::count(header.begin(), header.end(), ','));
  const std::optional<RunoutSample> back = parse_runout_csv_row(row);
  ASSERT_TRUE(back.has_value());
  EXPECT_EQ(back->front_x, s.front_x);
  EXPECT_EQ(back->front_z, s.front_z);
  EXPECT_EQ(back->tail_x, s.tail_x);
  EXPECT_EQ(back->tail_z, s.tail_z);
  RunoutMonitor flat(spec, FlumeCoordinates());
  const RunoutSample f = flat.sample(uniform_strip(1000, 2.0), 0.0, 0);
  EXPECT_EQ(f.front_x, f.front);
  EXPECT_EQ(f.tail_x, f.tail);
  EXPECT_TRUE(std::isnan(f.front_z) && std::isnan(f.tail_z));
  EXPECT_NE(runout_csv_row(f).find(",nan,"), std::string::npos);
  // a row of the thirteen older columns still reads (a restart in a folder written before), unlocated
  const std::string old = first_fields(row, kRunoutCsvColumnsBeforeLocation);
  const std::optional<RunoutSample> old_back = parse_runout_csv_row(old);
  ASSERT_TRUE(old_back.has_value()) << old;
  EXPECT_EQ(old_back->front, s.front);
  EXPECT_TRUE(std::isnan(old_back->front_x));
  RunoutSample located = *old_back;
  locate_front_and_tail(located, c);
  EXPECT_EQ(runout_csv_row(located), row);
}

TEST(Runout, MonitorDifferencesTheFrontAndMeasuresFromTheGate) {
  RunoutSpec spec;
  spec.enabled = true;
  RunoutMonitor monitor(spec, FlumeCoordinates());
  ParticleStore P = uniform_strip(200, 1.0);
  monitor.sample(P, 0.0, 0);
  for (std::size_t p = 0; p < P.size(); ++p) P.x[0][p] += 0.3;  // everything moved 0.3 m in 0.5 s
  const RunoutSample s = monitor.sample(P, 0.5, 10);
  EXPECT_NEAR(s.front_velocity, 0.6, 1e-12);
  RunoutResult r = monitor.result();
  EXPECT_FALSE(r.gate_from_scene);
  EXPECT_NEAR(r.from_gate, 0.3, 1e-12);  // from the initial front
  EXPECT_FALSE(r.beyond_runout_plane.has_value());
  spec.has_gate = true;
  spec.gate_x = 0.5;
  spec.has_runout_plane = true;
  spec.runout_plane_x = 1.0;
  RunoutMonitor given(spec, FlumeCoordinates());
  given.resume(monitor.first(), monitor.last());
  r = given.result();
  EXPECT_NEAR(r.from_gate, s.front - 0.5, 1e-12);
  EXPECT_NEAR(*r.beyond_runout_plane, s.front - 1.0, 1e-12);
}

// A layer on [0.2, 0.6) x [0, 0.2): particles of volume 1e-6 m^3 on a 0.01 m lattice in s and y, 4
// per column `dz` apart (0.04 m thick as volume per area: 4e-6 / 1e-4).
ParticleStore uniform_layer(double dz) {
  ParticleStore P;
  std::int64_t id = 0;
  for (int i = 0; i < 40; ++i)
    for (int j = 0; j < 20; ++j)
      for (int k = 0; k < 4; ++k)
        P.add(id++, Vec3(0.2 + (i + 0.5) * 0.01, (j + 0.5) * 0.01, (k + 0.5) * dz), Vec3::Zero(), 1.6e-3, 1e-6, 0);
  return P;
}

TEST(Deposit, UniformLayerHasItsThicknessAndVolumeIsConserved) {
  ParticleStore P = uniform_layer(0.01);
  P.add(static_cast<std::int64_t>(P.size()), Vec3(5.0, 0.1, 0.0), Vec3::Zero(), 1.6e-3, 1e-6, 0);  // a stray beyond the raster
  const DepositRaster d = measure_deposit(P, FlumeCoordinates(), 0.0, 1.0, 0.0, 0.2, 0.05);
  ASSERT_EQ(d.ns, 20);
  ASSERT_EQ(d.ny, 4);
  double volume = 0.0;
  for (int i = 0; i < d.ns; ++i)
    for (int j = 0; j < d.ny; ++j) {
      const double s = d.s_centre(i);
      EXPECT_NEAR(d.at(i, j), s > 0.2 && s < 0.6 ? 0.04 : 0.0, 1e-12) << "cell " << i << ", " << j;
      volume += d.at(i, j) * d.ds * d.dy;
    }
  EXPECT_NEAR(volume, 3200e-6, 1e-12);
  EXPECT_DOUBLE_EQ(d.volume_outside, 1e-6);
}

TEST(Deposit, TheSeededThicknessIsTheSameMassAtItsSeededVolume) {
  // The same layer loosened by a quarter (every volume 1.25 V0): thickness 0.05 m, seeded 0.04 m.
  ParticleStore P = uniform_layer(0.0125);
  for (std::size_t p = 0; p < P.size(); ++p) P.volume[p] = 1.25 * P.volume0[p];
  const DepositRaster d = measure_deposit(P, FlumeCoordinates(), 0.0, 1.0, 0.0, 0.2, 0.05);
  for (int i = 0; i < d.ns; ++i)
    for (int j = 0; j < d.ny; ++j) {
      const double s = d.s_centre(i);
      EXPECT_NEAR(d.at(i, j), s > 0.2 && s < 0.6 ? 0.05 : 0.0, 1e-12);
      EXPECT_NEAR(d.seeded_at(i, j), s > 0.2 && s < 0.6 ? 0.04 : 0.0, 1e-12);
    }
}

TEST(RunoutOutput, CsvRowRoundTrips) {
  RunoutSample r;
  r.time = 0.125;
  r.step = 77;
  r.mass = 6.1;
  r.front = 1.25;
  r.tail = -0.2;
  r.centre = Vec3(0.5, 0.01, 0.3);
  r.front_velocity = 0.7;
  const auto back = parse_runout_csv_row(runout_csv_row(r));
  ASSERT_TRUE(back.has_value());
  EXPECT_EQ(back->step, 77);
  EXPECT_EQ(back->front, 1.25);
  EXPECT_EQ(back->centre[2], 0.3);
  EXPECT_EQ(back->front_velocity, 0.7);
  r.centre_s = 1.0 / 3.0;  // exactly, not to 10 digits
  EXPECT_EQ(parse_runout_csv_row(runout_csv_row(r))->centre_s, 1.0 / 3.0);
  EXPECT_FALSE(parse_runout_csv_row("1,2,3").has_value());
}

// terrain.vtu draws the bed the particles slide on: the profile at the node columns, straight between
// them (it drew the profile, which a transition's arc lifts up to h^2/8r above that bed, and resting
// sand looked sunk into it), and says by how much the profile lies above it.
TEST(RunoutOutput, TerrainSurfaceReadsBackOnTheBed) {
  const TerrainProfile profile(flume_terrain(31.4, 0.2));
  const test::ScratchDir dir("test_terrain");
  const std::string path = (dir / "terrain.vtu").string();
  const double h = 0.05, w0 = 0.0;
  write_terrain_vtu(path, profile, -0.1, 2.4, -0.3, 0.3, 0.01, h, w0);
  vtkNew<vtkXMLUnstructuredGridReader> reader;
  reader->SetFileName(path.c_str());
  reader->Update();
  vtkUnstructuredGrid* g = reader->GetOutput();
  ASSERT_EQ(g->GetNumberOfPoints(), 2 * 251);  // 250 segments of 0.01 m; every node column is one of the samples
  EXPECT_EQ(g->GetNumberOfCells(), 250);
  ASSERT_NE(g->GetPointData()->GetArray("arc_length"), nullptr);
  ASSERT_NE(g->GetPointData()->GetArray("slope_angle"), nullptr);
  vtkDataArray* above = g->GetPointData()->GetArray("profile_above_bed");
  ASSERT_NE(above, nullptr);
  double lowest = 0.0, highest = 0.0;
  for (vtkIdType p = 0; p < g->GetNumberOfPoints(); ++p) {
    double x[3];
    g->GetPoint(p, x);
    EXPECT_DOUBLE_EQ(x[1], p % 2 == 0 ? -0.3 : 0.3);
    // the chord between the two node columns around x
    const double k = std::floor((x[0] + 0.1) / h + 1e-9), xl = -0.1 + k * h, xr = xl + h;
    const double chord = profile.height(xl) + (x[0] - xl) / h * (profile.height(xr) - profile.height(xl));
    EXPECT_NEAR(x[2], chord + w0, 1e-12) << x[0];
    EXPECT_NEAR(above->GetTuple1(p), profile.height(x[0]) - x[2], 1e-12) << x[0];
    lowest = std::min(lowest, above->GetTuple1(p));
    highest = std::max(highest, above->GetTuple1(p));
  }
  // the concave transition's arc (r = 0.2 m) sags below its chords, by at most h^2/(8 r cos^3 theta)
  // along z, theta = 31.4 deg where it meets the slope (docs/theory.md); the straight parts lie on them
  // (measured: 2.0 mm, 1.28 h^2/8r)
  const double sag_bound = h * h / (8 * 0.2 * std::pow(std::cos(31.4 * std::numbers::pi / 180.0), 3));
  EXPECT_LT(lowest, -h * h / (8 * 0.2));
  EXPECT_GE(lowest, -sag_bound - 1e-12);
  EXPECT_LE(highest, 1e-12);
  EXPECT_NEAR(g->GetPointData()->GetArray("slope_angle")->GetTuple1(0), 31.4, 1e-9);
}

// A sand block sliding on a flat floor, gravity tilted 31.4 deg down +x.
const char* kSlideScene = R"({
    "name": "slide", "grid": { "origin": [0, 0, 0], "size": [0.4, 0.02, 0.1], "cell_size": 0.02 },
    "gravity": [5.11, 0, -8.37], "time": { "end": 0.02 },
    "materials": { "sand": { "model": "drucker_prager", "density": 1600, "young": 2e6, "poisson": 0.3,
                             "friction_angle": 40, "cohesion": 10 } },
    "bodies": [ { "name": "b", "material": "sand", "box": { "min": [0.04, 0, 0], "max": [0.14, 0.02, 0.04] } } ],
    "boundaries": { "z-": { "type": "friction", "friction_coefficient": 0.554 }, "z+": "open" },
    "output": { "history_interval": 0.005 },
    "diagnostics": { "runout": { "gate_x": 0.14, "runout_plane_x": 0.3 } } })";

std::string read_text(const fs::path& path) {
  std::ifstream in(path);
  std::stringstream text;
  text << in.rdbuf();
  return text.str();
}

/// `scene` resumed from `checkpoint` (read from `path`) and run to its end through the run driver.
RunSummary run_resumed(const Scene& scene, const Checkpoint& checkpoint, const std::string& path, RunOptions options) {
  Solver resumed(scene);
  restore_checkpoint(resumed, checkpoint, path);
  options.resume = &checkpoint.run;
  return run_scene(resumed, options);
}

TEST(RunoutOutput, RunWritesRunoutHistoryAndDeposit) {
  Solver solver(parse_scene(kSlideScene, "slide"));
  const test::ScratchDir dir("test_runout_run");
  RunOptions options;
  options.out_dir = dir.path().string();
  options.progress = false;
  const RunSummary summary = run_scene(solver, options);
  ASSERT_TRUE(summary.runout.has_value());
  EXPECT_TRUE(summary.terrain_path.empty());  // flat: no terrain surface
  EXPECT_FALSE(fs::exists(dir / "terrain.vtu"));
  std::ifstream csv(dir / "runout.csv");
  std::string line;
  std::getline(csv, line);
  EXPECT_EQ(line, runout_csv_header());
  int rows = 0;
  std::optional<RunoutSample> last;
  while (std::getline(csv, line)) {
    last = parse_runout_csv_row(line);
    ASSERT_TRUE(last.has_value()) << line;
    ++rows;
  }
  EXPECT_EQ(rows, 1 + 4);  // t = 0 and every 0.005 s to 0.02 s
  EXPECT_NEAR(last->time, 0.02, 1e-12);
  EXPECT_NEAR(summary.runout->front, last->front, 1e-9);
  EXPECT_NEAR(summary.runout->from_gate, last->front - 0.14, 1e-9);
  EXPECT_NEAR(*summary.runout->beyond_runout_plane, last->front - 0.3, 1e-9);
  EXPECT_GT(last->centre_velocity_s, 0.0);  // it slides down +x
  {
    std::ifstream in(dir / "runout.json");
    const nlohmann::json j = nlohmann::json::parse(in);
    // (17 digits, as runout.csv: the numbers read back are the same doubles)
    EXPECT_EQ(j.at("time").get<double>(), last->time);
    EXPECT_EQ(j.at("front").get<double>(), last->front);
    EXPECT_EQ(j.at("tail").get<double>(), last->tail);
    EXPECT_NEAR(j.at("gate_s").get<double>(), 0.14, 1e-12);
    EXPECT_TRUE(j.at("gate_from_scene").get<bool>());
    EXPECT_EQ(j.at("beyond_runout_plane").get<double>(), *summary.runout->beyond_runout_plane);
    EXPECT_TRUE(j.at("all_left_time").is_null());
    EXPECT_EQ(j.at("outflow_mass_share").get<double>(), 0.0);  // nothing left: the open z+ is far above
    EXPECT_FALSE(j.at("limited_by_outflow").get<bool>());
    EXPECT_FALSE(j.at("front_at_grid_end").get<bool>());
  }
  // deposit.csv: one row per raster cell (20 x 1 cells of 0.02 m); the volume matches the particles'.
  std::ifstream dep(dir / "deposit.csv");
  std::getline(dep, line);
  EXPECT_EQ(line, "s,y,x,thickness,thickness_seeded");
  double volume = 0.0;
  rows = 0;
  while (std::getline(dep, line)) {
    double s, y, x, t;
    ASSERT_EQ(std::sscanf(line.c_str(), "%lf,%lf,%lf,%lf", &s, &y, &x, &t), 4) << line;
    volume += t * 0.02 * 0.02;
    ++rows;
  }
  EXPECT_EQ(rows, 20);
  double particle_volume = 0.0;
  for (double v : solver.particles().volume) particle_volume += v;
  EXPECT_NEAR(volume, particle_volume, 1e-6 * particle_volume);
}

TEST(RunoutOutput, RestartContinuesTheHistoryBitForBit) {
  Scene scene = parse_scene(kSlideScene, "slide");
  scene.output.checkpoint_interval = 0.012;  // one checkpoint, mid-run
  const test::ScratchDir dir("test_runout_restart");
  RunOptions options = test::quiet_run_options(dir);
  RunSummary whole;
  {
    Solver solver(scene);
    whole = run_scene(solver, options);
  }
  EXPECT_EQ(whole.frames_in_series, whole.frames);
  const std::string reference = read_text(dir / "runout.csv");
  const std::string reference_result = read_text(dir / "runout.json");
  const std::string checkpoint_path = (dir / "checkpoint.h5").string();
  const Checkpoint checkpoint = read_checkpoint(checkpoint_path);
  ASSERT_GT(checkpoint.solver.step, 0);
  const RunSummary rest = run_resumed(scene, checkpoint, checkpoint_path, options);
  // The series lists every frame again; this call wrote only those after the checkpoint (the run's
  // summary line said "(1 frames)").
  EXPECT_EQ(rest.frames_in_series, whole.frames);
  EXPECT_GT(rest.frames, 0u);
  EXPECT_LT(rest.frames, whole.frames);
  // The rows after the checkpoint are rewritten identically, front velocity included (it needs
  // the last row before the checkpoint), and the runout is measured from the same gate.
  EXPECT_EQ(read_text(dir / "runout.csv"), reference);
  EXPECT_EQ(read_text(dir / "runout.json"), reference_result);
}

// A folder written before runout.csv had front_x ... tail_z, resumed: the rows kept up to the
// checkpoint get the four columns (from their front and tail), so the file is the one an
// uninterrupted run writes now, not rows of thirteen columns under a header of seventeen.
TEST(RunoutOutput, RestartAddsTheFrontsPlaceToAnOlderHistory) {
  Scene scene = parse_scene(kSlideScene, "slide");
  scene.output.checkpoint_interval = 0.012;  // one checkpoint, mid-run
  const test::ScratchDir dir("test_runout_restart_older");
  RunOptions options = test::quiet_run_options(dir);
  {
    Solver solver(scene);
    run_scene(solver, options);
  }
  const std::string reference = read_text(dir / "runout.csv");
  {
    // the history as the older talus wrote it: every line cut after its thirteenth field
    std::istringstream in(reference);
    std::string older;
    for (std::string line; std::getline(in, line);) older += first_fields(line, kRunoutCsvColumnsBeforeLocation) + "\n";
    ASSERT_EQ(older.find("front_x"), std::string::npos);
    std::ofstream(dir / "runout.csv") << older;
  }
  const std::string checkpoint_path = (dir / "checkpoint.h5").string();
  const Checkpoint checkpoint = read_checkpoint(checkpoint_path);
  ASSERT_GT(checkpoint.solver.step, 0);
  run_resumed(scene, checkpoint, checkpoint_path, options);
  EXPECT_EQ(read_text(dir / "runout.csv"), reference);
}

// runout.json says how the run ended and which state it describes: a run stopped between history
// rows gave the row before the stop, and nothing said that it was not the end; an unstable run wrote
// none; one stopped at time.max_steps is completed (as run.json says) with its deposit, but not final.
TEST(RunoutOutput, TheResultSaysHowTheRunEndedAndTheStateItDescribes) {
  const Scene scene = parse_scene(kSlideScene, "slide");
  const test::ScratchDir dir("test_runout_status");
  auto result_of = [](const fs::path& folder) {
    std::ifstream in(folder / "runout.json");
    return nlohmann::json::parse(in);
  };
  RunOptions options = test::quiet_run_options(dir / "whole");
  RunSummary whole;
  {
    Solver solver(scene);
    whole = run_scene(solver, options);
  }
  nlohmann::json j = result_of(dir / "whole");
  EXPECT_EQ(j.at("status"), "completed");
  EXPECT_TRUE(j.at("final").get<bool>());
  EXPECT_EQ(j.at("step").get<std::int64_t>(), whole.steps);
  {
    // --stop-after at once: stopped after the first step, with the last history row at t = 0
    Solver solver(scene);
    options.out_dir = (dir / "stopped").string();
    options.deadline = std::chrono::steady_clock::now();
    const RunSummary stopped = run_scene(solver, options);
    options.deadline.reset();
    ASSERT_TRUE(stopped.stopped_at_deadline);
    j = result_of(dir / "stopped");
    EXPECT_EQ(j.at("status"), "interrupted");
    EXPECT_FALSE(j.at("final").get<bool>());
    EXPECT_EQ(j.at("step").get<std::int64_t>(), 1);
    EXPECT_EQ(j.at("time").get<double>(), solver.time());  // where it stopped, not the row at t = 0
    EXPECT_GT(solver.time(), 0.0);
    EXPECT_EQ(j.at("front").get<double>(), stopped.runout->front);
    EXPECT_FALSE(fs::exists(dir / "stopped" / "deposit.csv"));
    // resumed to the end: the uninterrupted run's result, to the bit
    const std::string checkpoint_path = (dir / "stopped" / "checkpoint.h5").string();
    run_resumed(scene, read_checkpoint(checkpoint_path), checkpoint_path, options);
    EXPECT_EQ(read_text(dir / "stopped" / "runout.json"), read_text(dir / "whole" / "runout.json"));
  }
  {
    Scene capped = scene;
    capped.max_steps = 5;
    Solver solver(capped);
    options.out_dir = (dir / "capped").string();
    run_scene(solver, options);
    j = result_of(dir / "capped");
    EXPECT_EQ(j.at("status"), "completed");
    EXPECT_FALSE(j.at("final").get<bool>());
    EXPECT_EQ(j.at("step").get<std::int64_t>(), 5);
    EXPECT_TRUE(fs::exists(dir / "capped" / "deposit.csv"));
  }
  {
    // a CFL breach in the first step: the last good state is the start, and its runout is written
    Scene fast = scene;
    fast.bodies[0].velocity = Vec3(200.0, 0.0, 0.0);
    fast.guards.max_step_displacement = 0.1;
    Solver solver(fast);
    options.out_dir = (dir / "unstable").string();
    EXPECT_THROW(run_scene(solver, options), Error);
    j = result_of(dir / "unstable");
    EXPECT_EQ(j.at("status"), "unstable");
    EXPECT_FALSE(j.at("final").get<bool>());
    EXPECT_EQ(j.at("step").get<std::int64_t>(), 0);
    EXPECT_EQ(j.at("time").get<double>(), 0.0);
  }
}

// talus run --restart DIR/checkpoint.h5 --out OTHER: the rows before the checkpoint stay in DIR.
// The monitor lost them: the default gate became the front at the checkpoint (18% short on a
// flume) and the first row's front velocity was 0.
TEST(RunoutOutput, RestartIntoAnotherFolderMeasuresFromTheSameGate) {
  Scene scene = parse_scene(kSlideScene, "slide");
  scene.output.checkpoint_interval = 0.012;  // one checkpoint, mid-run
  scene.runout.has_gate = false;             // the gate is the initial front
  const test::ScratchDir dir("test_runout_restart_elsewhere");
  RunOptions options = test::quiet_run_options(dir / "first");
  {
    Solver solver(scene);
    run_scene(solver, options);
  }
  const std::string reference = read_text(dir / "first" / "runout.csv");
  const std::string checkpoint_path = (dir / "first" / "checkpoint.h5").string();
  const Checkpoint checkpoint = read_checkpoint(checkpoint_path);
  ASSERT_GT(checkpoint.solver.step, 0);
  options.out_dir = (dir / "second").string();
  options.resume_dir = (dir / "first").string();
  run_resumed(scene, checkpoint, checkpoint_path, options);
  // The same result, and the new history is the reference's rows after the checkpoint, under the header.
  EXPECT_EQ(read_text(dir / "second" / "runout.json"), read_text(dir / "first" / "runout.json"));
  const std::string rest = read_text(dir / "second" / "runout.csv");
  const std::size_t header_end = rest.find('\n') + 1;
  ASSERT_GT(rest.size(), header_end);
  EXPECT_EQ(reference.substr(0, header_end), rest.substr(0, header_end));
  const std::string rows = rest.substr(header_end);
  ASSERT_GE(reference.size(), rows.size());
  EXPECT_EQ(reference.substr(reference.size() - rows.size()), rows);
  EXPECT_EQ(read_text(dir / "first" / "runout.csv"), reference);  // the checkpoint's folder is read, not changed
}

// Mass that leaves through the open faces is not in the front and tail quantiles. A block thrown
// off the grid's x+ end gave the grid's end as its front, with most of its mass gone and nothing in
// runout.json to say so. Now runout.json says what share left, through x+ (ahead of the front) and in
// all, and flags the front as limited by outflow; the share through x+ travels in the checkpoint.
const char* kOutflowScene = R"({
    "name": "outflow", "grid": { "origin": [0, 0, 0], "size": [0.4, 0.1, 0.1], "cell_size": 0.02 },
    "time": { "end": 0.01 },
    "materials": { "sand": { "model": "drucker_prager", "density": 1600, "young": 2e6, "poisson": 0.3,
                             "friction_angle": 40, "cohesion": 10 } },
    "bodies": [ { "name": "ahead", "material": "sand", "velocity": [12, 0, 0],
                  "box": { "min": [0.26, 0, 0], "max": [0.36, 0.04, 0.04] } },
                { "name": "side", "material": "sand", "velocity": [0, 3, 0],
                  "box": { "min": [0.04, 0.04, 0], "max": [0.12, 0.08, 0.04] } } ],
    "boundaries": { "x+": "open", "y+": "open", "z+": "open" },
    "output": { "history_interval": 0.0025, "checkpoint_interval": 0.005 },
    "diagnostics": { "runout": { "gate_x": 0.1 } } })";

TEST(RunoutOutput, MassLeftThroughTheOpenFacesIsSaidAndTheFrontFlagged) {
  const test::ScratchDir dir("test_runout_outflow");
  RunOptions options = test::quiet_run_options(dir / "both");
  auto result_of = [](const fs::path& folder) {
    std::ifstream in(folder / "runout.json");
    return nlohmann::json::parse(in);
  };
  double energy_available = 0.0;
  OutflowFaces faces;
  {
    Solver solver(parse_scene(kOutflowScene, "outflow"));
    energy_available = run_scene(solver, options).energy_available;
    faces = solver.outflow_faces();
    double in_grid = 0.0;
    for (double m : solver.particles().mass) in_grid += m;
    const double total = in_grid + solver.outflow_mass();
    const nlohmann::json j = result_of(dir / "both");
    // most of the block thrown at x+ left through it, and some of the other through y+
    EXPECT_GT(solver.outflow_mass_x_plus(), 0.3 * total);
    EXPECT_LT(solver.outflow_mass_x_plus(), solver.outflow_mass());
    EXPECT_NEAR(j.at("outflow_mass_share").get<double>(), solver.outflow_mass() / total, 1e-12);
    EXPECT_NEAR(j.at("outflow_mass_share_x_plus").get<double>(), solver.outflow_mass_x_plus() / total, 1e-12);
    EXPECT_TRUE(j.at("limited_by_outflow").get<bool>());
    EXPECT_TRUE(j.at("front_at_grid_end").get<bool>());
  }
  {
    // Resumed from its checkpoint (t = 0.005 s, after some of the block had left): the same result,
    // so the share through x+ before the checkpoint was kept.
    const std::string checkpoint_path = (dir / "both" / "checkpoint.h5").string();
    const Checkpoint checkpoint = read_checkpoint(checkpoint_path);
    ASSERT_GT(checkpoint.solver.outflow_faces.mass[OutflowFaces::kXPlus], 0.0);
    Solver resumed(parse_scene(kOutflowScene, "outflow"));
    restore_checkpoint(resumed, checkpoint, checkpoint_path);
    const std::string whole = read_text(dir / "both" / "runout.json");
    RunOptions again = options;
    again.resume = &checkpoint.run;
    // and the energy available: the guard's floor counts the mass that had left (it was recomputed
    // from the particles still there, and run.json's figure changed with the restart)
    EXPECT_EQ(run_scene(resumed, again).energy_available, energy_available);
    EXPECT_EQ(read_text(dir / "both" / "runout.json"), whole);
    // and what left through each face, the faces the checkpoint saved included
    ASSERT_GT(faces.particles[3], 0);  // y+
    const OutflowFaces resumed_faces = resumed.outflow_faces();
    EXPECT_EQ(resumed_faces.particles, faces.particles);
    EXPECT_EQ(std::memcmp(resumed_faces.mass.data(), faces.mass.data(), sizeof(faces.mass)), 0);
  }
  {
    // Only the block that leaves sideways: the share is said, but the front is not limited by it.
    Scene scene = parse_scene(kOutflowScene, "outflow");
    scene.bodies.erase(scene.bodies.begin());
    Solver solver(scene);
    options.out_dir = (dir / "side").string();
    run_scene(solver, options);
    const nlohmann::json j = result_of(dir / "side");
    EXPECT_GT(j.at("outflow_mass_share").get<double>(), 0.05);
    EXPECT_EQ(j.at("outflow_mass_share_x_plus").get<double>(), 0.0);
    EXPECT_FALSE(j.at("limited_by_outflow").get<bool>());
    EXPECT_FALSE(j.at("front_at_grid_end").get<bool>());
  }
}

TEST(RunoutSpec, BadDiagnosticsKeysAreRefusedNamingTheKey) {
  auto error_of = [](const std::string& runout) {
    std::string json = kSlideScene;
    const std::string given = R"({ "gate_x": 0.14, "runout_plane_x": 0.3 })";
    json.replace(json.find(given), given.size(), runout);
    try {
      parse_scene(json, "slide");
    } catch (const Error& e) {
      EXPECT_EQ(e.exit_code(), 2);
      return std::string(e.what());
    }
    return std::string("no error");
  };
  EXPECT_NE(error_of(R"({ "front_quantile": 1.5 })").find("diagnostics.runout.front_quantile = 1.5 is outside the allowed range [0.5, 1]"),
            std::string::npos);
  EXPECT_NE(error_of(R"({ "deposit_cell": 0 })").find("diagnostics.runout.deposit_cell = 0 is outside the allowed range (0"),
            std::string::npos);
  EXPECT_NE(error_of(R"({ "deposit_cell": 1e-6 })").find("at most 1e7"), std::string::npos);
  EXPECT_NE(error_of(R"({ "front": 0.9 })").find("unknown key diagnostics.runout.front"), std::string::npos);
  // Defaults resolved and echoed.
  std::string json = kSlideScene;
  const std::string given = R"({ "gate_x": 0.14, "runout_plane_x": 0.3 })";
  json.replace(json.find(given), given.size(), "{}");
  const Scene s = parse_scene(json, "slide");
  EXPECT_TRUE(s.runout.enabled);
  EXPECT_EQ(s.runout.deposit_cell, 0.02);
  EXPECT_FALSE(s.runout.has_gate);
  const Scene echoed = parse_scene(scene_to_json(s).dump(), "echo");
  EXPECT_TRUE(echoed.runout.enabled);
  EXPECT_EQ(echoed.runout.front_quantile, 0.995);
}

}  // namespace
}  // namespace runout_test
}  // namespace talus
