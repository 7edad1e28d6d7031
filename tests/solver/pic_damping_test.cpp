// solver.pic_fraction: the PIC share of the G2P update removes kinetic energy, and the budget counts
// exactly what it removes (EnergyBudget::damping), independently of the thread count.
#include "scene_fixtures.hpp"
#include "talus/solver/solver.hpp"

#include <gtest/gtest.h>
#include <omp.h>

#include <cmath>
#include <cstring>

namespace talus {
namespace pic_damping_test {
namespace {

struct Gap {
  double gap = 0.0, damping = 0.0, kinetic0 = 0.0;
};

Gap run(double pic, int threads = 2) {
  omp_set_num_threads(threads);
  Scene scene = test::tumbling_block_scene(0.1);
  scene.pic_fraction = pic;
  Solver solver(scene);
  const EnergyBudget e0 = solver.energies();
  while (!solver.finished()) solver.step();
  const EnergyBudget e1 = solver.energies();
  return {e1.total() - e0.total(), e1.damping, e0.kinetic};
}

TEST(PicDamping, TheBudgetCountsWhatThePicShareRemoves) {
  const Gap flip = run(0.0), pic = run(0.05);
  std::printf("FLIP gap %.4e J; PIC 5%%: gap %.4e J, damping %.4e J (initial kinetic %.4e J)\n", flip.gap, pic.gap,
              pic.damping, pic.kinetic0);
  EXPECT_EQ(flip.damping, 0.0);
  EXPECT_GT(pic.damping, 0.01 * pic.kinetic0);  // it damps noticeably
  // Without the damping term the budget would open by `damping`; with it, it closes as well as FLIP's.
  EXPECT_LT(std::abs(pic.gap - flip.gap), 0.1 * pic.damping);
}

TEST(PicDamping, BitIdenticalForOneAndTwoThreads) {
  omp_set_num_threads(1);
  Scene scene = test::tumbling_block_scene(0.05);
  scene.pic_fraction = 0.05;
  Solver a(scene);
  while (!a.finished()) a.step();
  omp_set_num_threads(2);
  Solver b(scene);
  while (!b.finished()) b.step();
  ASSERT_EQ(a.particles().size(), b.particles().size());
  for (int d = 0; d < 3; ++d)
    EXPECT_EQ(0, std::memcmp(a.particles().v[d].data(), b.particles().v[d].data(), a.particles().size() * sizeof(double)));
  EXPECT_EQ(a.energies().damping, b.energies().damping);
}

}  // namespace
}  // namespace pic_damping_test
}  // namespace talus
