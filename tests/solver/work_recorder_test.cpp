// The work recorder's choice of steps (solver/work_recorder.hpp): a bench keeps its first steps; a
// run's record, once full, thins itself so that it keeps sampling the whole run evenly.
#include "talus/solver/work_recorder.hpp"

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include <cstdint>
#include <numeric>
#include <sstream>
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

TEST(WorkRecorder, ARunRecordOfAHugeSceneStaysWithinItsEntries) {
  // Each step's loop holds a quarter of the bound: the record thins itself by its entries, not only
  // by its 1000 steps, and still spans the run at one even spacing.
  const std::size_t per_step = WorkRecorder::kMaxRunBlockEntries / 4;
  WorkRecorder run(1000, 1, RecordSpan::WholeRun);
  for (std::int64_t step = 0; step < 40; ++step) {
    if (run.begin_step(step, per_step, per_step))
      run.add_unit_loop("stress", std::vector<double>(per_step, 1e-9), std::vector<std::uint32_t>(per_step, 8), 1e-3);
    run.end_step(2e-3);
    EXPECT_LE(run.block_entries(), WorkRecorder::kMaxRunBlockEntries) << step;
  }
  ASSERT_GE(run.steps().size(), 2u);
  EXPECT_LE(run.steps().size(), 4u);
  EXPECT_EQ(run.block_entries(), run.steps().size() * per_step);
  EXPECT_EQ(run.steps().front().step, 0);
  for (std::size_t k = 1; k < run.steps().size(); ++k)
    EXPECT_EQ(run.steps()[k].step - run.steps()[k - 1].step, run.interval()) << k;
  EXPECT_GT(run.steps().back().step, 40 - run.interval() - 1);
  // A bench's record keeps the steps it was asked for, whatever their size.
  WorkRecorder bench(6);
  for (std::int64_t step = 0; step < 6; ++step) {
    ASSERT_TRUE(bench.begin_step(step, per_step, per_step));
    bench.add_unit_loop("stress", std::vector<double>(per_step, 1e-9), std::vector<std::uint32_t>(per_step, 8), 1e-3);
    bench.end_step(2e-3);
  }
  EXPECT_EQ(bench.steps().size(), 6u);
}

TEST(WorkRecorder, WritesOneLineOfJsonWithEveryStepAndRegion) {
  WorkRecorder run(10, 1, RecordSpan::WholeRun);
  for (std::int64_t step = 0; step < 3; ++step) {
    run.begin_step(step, 16, 2);
    run.add_static("grid clear", 5, 1, 1e-5);
    run.add_unit_loop("stress", {1e-6, 2e-6}, {7, 9}, 4e-6);
    run.add_serial("glue", 1e-6);
    run.end_step(1e-4);
  }
  run.set_totals({.steps = 3, .solver_seconds = 3e-4});
  std::ostringstream out;
  run.write_json(out, nlohmann::json{{"scene", "a \"quoted\" name"}, {"threads", 2}});
  const std::string text = out.str();
  ASSERT_FALSE(text.empty());
  EXPECT_EQ(text.find('\n'), text.size() - 1);  // one line
  const nlohmann::json j = nlohmann::json::parse(text);
  EXPECT_EQ(j["format"], "talus-work-record/1");
  EXPECT_EQ(j["scene"], "a \"quoted\" name");
  EXPECT_EQ(j["threads"], 2);
  EXPECT_EQ(j["record_interval"], 1);
  EXPECT_EQ(j["run_steps"], 3);
  ASSERT_EQ(j["steps"].size(), 3u);
  const nlohmann::json& last = j["steps"][2];
  EXPECT_EQ(last["step"], 2);
  EXPECT_EQ(last["particles"], 16);
  ASSERT_EQ(last["regions"].size(), 3u);
  EXPECT_EQ(last["regions"][0]["schedule"], "static");
  EXPECT_EQ(last["regions"][0]["items"], 5);
  EXPECT_EQ(last["regions"][1]["schedule"], "dynamic");
  EXPECT_EQ(last["regions"][1]["block_particles"], (std::vector<int>{7, 9}));
  EXPECT_EQ(last["regions"][1]["block_seconds"], (std::vector<double>{1e-6, 2e-6}));
  EXPECT_EQ(last["regions"][2]["schedule"], "serial");
}

}  // namespace
}  // namespace talus
