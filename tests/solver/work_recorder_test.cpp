// The work recorder's choice of steps (solver/work_recorder.hpp): a bench keeps its first steps; a
// run's record, once full, thins itself so that it keeps sampling the whole run evenly.
#include "talus/solver/work_recorder.hpp"

#include <gtest/gtest.h>

#include <cstdint>
#include <numeric>
#include <vector>

namespace talus {
namespace {

/// Offers steps 0 .. n-1 to the recorder as the solver does and returns the recorded steps' numbers.
std::vector<std::int64_t> offer_steps(WorkRecorder& recorder, std::int64_t n) {
  for (std::int64_t step = 0; step < n; ++step) {
    const bool recorded = recorder.begin_step(step, 100, 10);
    EXPECT_EQ(recorded, recorder.active());
    recorder.add_serial("glue", 1e-6);
    recorder.end_step(2e-6);
    EXPECT_FALSE(recorder.active());
    EXPECT_EQ(recorder.last_step_recorded(), recorded);
  }
  std::vector<std::int64_t> steps;
  for (const WorkStep& s : recorder.steps()) steps.push_back(s.step);
  return steps;
}

TEST(WorkRecorder, ABenchRecordKeepsItsFirstSteps) {
  WorkRecorder recorder(4, 3);
  EXPECT_EQ(offer_steps(recorder, 100), (std::vector<std::int64_t>{0, 3, 6, 9}));
  EXPECT_EQ(recorder.interval(), 3);
}

TEST(WorkRecorder, ARunRecordThinsItselfToSpanTheWholeRun) {
  WorkRecorder recorder(4, 1, RecordSpan::WholeRun);
  EXPECT_EQ(offer_steps(recorder, 10), (std::vector<std::int64_t>{0, 3, 6, 9}));
  EXPECT_EQ(recorder.interval(), 3);
  // 1000 steps every 7th, at most 10 kept: the record reaches the run's end at one even spacing.
  WorkRecorder run(10, 7, RecordSpan::WholeRun);
  const std::vector<std::int64_t> steps = offer_steps(run, 1000);
  ASSERT_GE(steps.size(), 5u);
  EXPECT_LE(steps.size(), 10u);
  EXPECT_EQ(steps.front(), 0);
  EXPECT_GT(steps.back(), 1000 - run.interval() - 1);  // the last due step was recorded
  for (std::size_t k = 1; k < steps.size(); ++k) EXPECT_EQ(steps[k] - steps[k - 1], run.interval()) << k;
  EXPECT_EQ(run.interval() % 7, 0);
  // An interval coprime with the sort's 20-step cadence stays so: sort steps are not over-sampled.
  EXPECT_EQ(std::gcd(run.interval(), 20), 1) << run.interval();
  // Each kept step still holds its own regions.
  for (const WorkStep& s : run.steps()) {
    ASSERT_EQ(s.regions.size(), 1u);
    EXPECT_EQ(s.regions[0].name, "glue");
    EXPECT_EQ(s.seconds, 2e-6);
  }
}

}  // namespace
}  // namespace talus
