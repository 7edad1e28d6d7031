// The MUSL remap scattered inside the G2P pass (gather_from_grid with remap = true) must give the
// nodal momentum of the separate remap scatter (scatter_to_grid, ScatterFields::Momentum) after a
// plain G2P, bit for bit: the same weights, the same colour order, the same per-node sums. And the
// particles must come out of both the same.
#include "talus/grid/grid.hpp"
#include "talus/grid/terrain.hpp"
#include "talus/particles/cell_sort.hpp"
#include "talus/particles/particle_store.hpp"
#include "talus/shape/bspline.hpp"
#include "talus/shape/gimp.hpp"
#include "talus/shape/linear.hpp"
#include "talus/transfer/transfers.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <random>
#include <span>

namespace talus {
namespace transfer_test {
namespace {

template <class Shape>
void check_fused_remap() {
  GridGeometry g;
  g.origin = Vec3(0.0, 0.0, 0.0);
  g.h = 0.1;
  g.cells = {12, 12, 12};
  Grid grid(g);
  ParticleStore P;
  std::mt19937 rng(3);
  std::uniform_real_distribution<double> pos(0.25, 0.95), vel(-1.0, 1.0), width(0.01, 0.07);
  for (int i = 0; i < 3000; ++i)
    P.add(i, Vec3(pos(rng), pos(rng), pos(rng)), Vec3(vel(rng), vel(rng), vel(rng)), 1.0 + 0.5 * vel(rng), 1.25e-4, 0);
  if constexpr (Shape::kDomain == DomainSource::Current) {
    P.enable_domain_state();  // half widths 0.1..0.7 cells: both the 3-node and the 4-node stencils
    for (std::size_t p = 0; p < P.size(); ++p)
      for (int d = 0; d < 3; ++d) P.domain[d][p] = width(rng);
  }
  CellSort sort(grid, Shape::kReachLow, Shape::kReachHigh);
  sort.sort(P, grid);
  grid.clear_active();
  // Node fields as a grid update would leave them: an acceleration share and v^L, varying per node.
  for (std::uint32_t t : grid.active_tiles())
    for (int s = 0; s < kTileNodes; ++s) {
      const std::size_t n = static_cast<std::size_t>(t) * kTileNodes + s;
      for (int d = 0; d < 3; ++d) {
        grid.force[d][n] = 0.01 * std::sin(0.37 * n + d);
        grid.velocity_l[d][n] = std::cos(0.11 * n + 2 * d);
      }
    }
  std::array<std::vector<double>, 3> displacement_arrays;
  for (auto& a : displacement_arrays) a.assign(P.size(), 0.0);
  const std::array<std::span<double>, 3> displacement = {displacement_arrays[0], displacement_arrays[1], displacement_arrays[2]};
  std::vector<double> damping(sort.block_count(), 0.0);
  ParticleStore separate = P;
  GatherOptions options;
  options.dt = 1e-3;
  gather_from_grid<Shape, FlatTerrain>(separate, sort, grid, displacement, damping, options);
  grid.clear_momentum();
  scatter_to_grid<Shape, FlatTerrain>(separate, sort, grid, ScatterFields::Momentum);
  std::array<std::vector<double>, 3> expected;
  for (int d = 0; d < 3; ++d)
    for (std::uint32_t t : grid.active_tiles())
      for (int s = 0; s < kTileNodes; ++s) expected[d].push_back(grid.momentum[d][static_cast<std::size_t>(t) * kTileNodes + s]);

  ParticleStore fused = P;
  grid.clear_momentum();
  options.remap = true;
  gather_from_grid<Shape, FlatTerrain>(fused, sort, grid, displacement, damping, options);
  double largest = 0.0;
  for (int d = 0; d < 3; ++d) {
    std::size_t k = 0;
    for (std::uint32_t t : grid.active_tiles())
      for (int s = 0; s < kTileNodes; ++s, ++k) {
        const double got = grid.momentum[d][static_cast<std::size_t>(t) * kTileNodes + s];
        ASSERT_EQ(got, expected[d][k]) << Shape::kName << " node " << t * kTileNodes + s << " axis " << d;
        largest = std::max(largest, std::abs(got));
      }
    for (std::size_t p = 0; p < P.size(); ++p) ASSERT_EQ(fused.v[d][p], separate.v[d][p]) << Shape::kName << " particle " << p;
  }
  EXPECT_GT(largest, 0.1);  // the comparison saw real momentum
}

TEST(Transfers, RemapInTheGatherPassEqualsTheSeparateRemapBitForBit) {
  check_fused_remap<LinearShape>();
  check_fused_remap<QuadraticBSplineShape>();
  check_fused_remap<UGimpShape>();
  check_fused_remap<CpGimpShape>();
}

}  // namespace
}  // namespace transfer_test
}  // namespace talus
