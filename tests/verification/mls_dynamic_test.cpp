// MLS smoothing on the dynamic benchmarks (Edo & Matsubara 2015, sec. 4(2)-(3)): the dynamic bar (Fig. 9-10,
// eq. 63) and the block between walls (Fig. 12-13). Numbers: docs/verification.md.
#include "mls_runs.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <initializer_list>
#include <vector>

namespace talus {
namespace mls_dynamic_test {
namespace {

using test::benchmark_scene;
using test::with_mls;

// The wave behind the front is -E v0 / c; without MLS it is jagged (MPM) or rippled (GIMP).
TEST(MlsDynamicBar, SmoothingRemovesTheRippleBehindTheFront) {
  for (ShapeKind shape : {ShapeKind::Linear, ShapeKind::CpGimp}) {
    const Scene s = benchmark_scene("dynamic_bar", shape, SchemeKind::Musl);
    const auto off = test::bar(s, "off");
    const auto cubic = test::bar(with_mls(s, MlsBasis::Cubic, 2.0, "x"), "cubic x");
    const auto linear = test::bar(with_mls(s, MlsBasis::Linear, 2.0, "xyz"), "linear xyz");
    // measured roughness (RMS second difference / exact): linear MPM 0.214 -> 0.073 (cubic x),
    // 0.069 (linear xyz); cpGIMP 0.061 -> 0.019, 0.017. Mean / exact: 1.015 -> 1.018, 1.022 (MPM),
    // 1.016 -> 1.017, 1.024 (cpGIMP): the level is kept within the 3% of the unsmoothed test.
    EXPECT_LT(cubic.roughness, off.roughness / 2.5) << to_string(shape);
    EXPECT_LT(linear.roughness, off.roughness / 2.5) << to_string(shape);
    EXPECT_NEAR(cubic.ratio, 1.0, 0.03) << to_string(shape);
    EXPECT_NEAR(linear.ratio, 1.0, 0.03) << to_string(shape);
  }
}

// The smoother itself neither feeds nor drains energy: the dynamic bar run on for 12 wave transits
// (0.5 s) against its fixed (bilateral) end. Measured max |E/E0 - 1|: cpGIMP 2.60% without MLS,
// 2.54% with the cubic-x fit (final -1.93%, -1.89%): the loss is the wall impact's, MLS changes it
// by less than 0.1% of E0.
TEST(MlsDynamicBar, EnergyOverTwelveTransitsMatchesTheUnsmoothedRun) {
  Scene s = benchmark_scene("dynamic_bar", ShapeKind::CpGimp, SchemeKind::Musl);
  s.end_time = 0.5;
  const auto off = test::walls(s, "bar off");
  const auto on = test::walls(with_mls(s, MlsBasis::Cubic, 2.0, "x"), "bar cubic x");
  EXPECT_LT(std::max(on.max_gain, on.max_loss), 0.03);
  EXPECT_NEAR(on.final_drift, off.final_drift, 0.002);
}

// Block between unilateral walls (Edo & Matsubara 2015, Fig. 12-13), through its first impact (t = 11.25 s).
// Target (issue 4): total energy within +-1% through 4 impacts with MLS; measured values for the
// full run are in docs/verification.md. Each impact changes the energy by several percent with or
// without MLS (the wall contact's own error, not the smoother's), so what is asserted here is that
// smoothing changes the energy of one impact by less than 2% of E0. Measured through t = 15 s:
//   without main's wall fix (5260c4c): final +15.1% without MLS, +13.7% with (gain at the wall);
//   with it:                           final  -9.4% without MLS, -10.6% with (loss at the wall).
// inputs/benchmarks/dynamic_bar_mls.json and block_between_walls_mls.json: the runs above (cpGIMP bar,
// uGIMP block) with a plain `talus run`.
TEST(MlsDynamicBar, ShippedInputIsTheVerifiedConfiguration) { test::expect_shipped_mls_input("dynamic_bar", ShapeKind::CpGimp); }
TEST(MlsBlockBetweenWalls, ShippedInputIsTheVerifiedConfiguration) {
  test::expect_shipped_mls_input("block_between_walls", ShapeKind::UGimp);
}

TEST(MlsBlockBetweenWalls, SmoothingChangesTheEnergyOfOneImpactByLessThanTwoPercent) {
  Scene s = benchmark_scene("block_between_walls", ShapeKind::CpGimp, SchemeKind::Musl);
  s.end_time = 15.0;
  const auto off = test::walls(s, "walls off");
  const auto on = test::walls(with_mls(s, MlsBasis::Cubic, 2.0, "x"), "walls cubic x");
  EXPECT_NEAR(on.final_drift, off.final_drift, 0.02);
  EXPECT_GT(std::abs(off.final_drift), 0.02);  // the impact itself does change the energy
}

/// The block between walls with cell h along the bar and a one-cell cross-section (as
/// tools/mls_walls_resolution.py refines it).
Scene refined_walls(double h, ShapeKind shape) {
  Scene s = benchmark_scene("block_between_walls", shape, SchemeKind::Musl);
  s.grid.cells = {static_cast<int>(std::lround(50.0 / h)), 1, 1};
  s.grid.h = h;
  for (BodySpec& b : s.bodies)
    for (int d = 1; d < 3; ++d) b.box_max[d] = b.box_min[d] + h;
  return s;
}

/// Total energy / initial at the times asked for (in increasing order), stepping to each.
std::vector<double> energy_at(const Scene& s, std::initializer_list<double> times) {
  Scene run = s;
  run.end_time = *std::max_element(times.begin(), times.end());
  Solver solver(run);
  const double e0 = solver.energies().total();
  std::vector<double> e;
  for (double t : times) {
    while (solver.time() < t && !solver.finished()) solver.step();
    e.push_back(solver.energies().total() / e0);
  }
  return e;
}

// Which part of the walls' energy error is whose (tools/mls_walls_resolution.py, cell 0.5 to
// 0.0625): the first impact (11.25 s, about 0.45 s of contact) loses a share that halves with
// the cell, cpGIMP 9.7%, 4.8%, 2.4%, 1.2%, with or without MLS: the no-rebound contact stops the
// wall node's share of the mass, an inelastic collision of a shrinking share. The flight back
// gains energy in the cell crossings, cpGIMP +3.0% at cell 0.5 (+32% at 0.0625), and MLS
// removes most of that: +0.4% (+0.9%). So the issue's +-1% through 4 impacts at cell 0.5 is
// the contact's to meet, not the smoother's.
TEST(MlsBlockBetweenWalls, ImpactLossHalvesWithTheCellAndSmoothingRemovesTheFlightDrift) {
  const auto coarse = energy_at(refined_walls(0.5, ShapeKind::CpGimp), {11.0, 12.5});
  const auto fine = energy_at(refined_walls(0.25, ShapeKind::CpGimp), {11.0, 12.5});
  const double loss_coarse = 1.0 - coarse[1] / coarse[0], loss_fine = 1.0 - fine[1] / fine[0];
  std::printf("walls impact loss: cell 0.5 %.5f, cell 0.25 %.5f\n", loss_coarse, loss_fine);
  EXPECT_GT(loss_coarse, 0.05);  // measured 0.097
  EXPECT_NEAR(loss_fine / loss_coarse, 0.5, 0.1);  // first order in the cell: measured 0.49

  const Scene off = refined_walls(0.5, ShapeKind::CpGimp);
  const auto flight_off = energy_at(off, {12.5, 31.0});
  const auto flight_on = energy_at(with_mls(off, MlsBasis::Cubic, 2.0, "x"), {12.5, 31.0});
  const double drift_off = flight_off[1] / flight_off[0] - 1.0, drift_on = flight_on[1] / flight_on[0] - 1.0;
  std::printf("walls flight 12.5-31 s: without MLS %+.5f, with %+.5f\n", drift_off, drift_on);
  EXPECT_GT(drift_off, 0.015);                    // measured +0.030
  EXPECT_LT(std::abs(drift_on), drift_off / 4.0);  // measured +0.0037
}

}  // namespace
}  // namespace mls_dynamic_test
}  // namespace talus
