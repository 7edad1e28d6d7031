// BackgroundWriter: one job at a time on a thread of its own; a job's exception reaches the thread
// that waits for it, once; a failed job stops the next from starting; the destructor waits.
#include "talus/core/error.hpp"
#include "talus/io/background_writer.hpp"

#include <gtest/gtest.h>

#include <atomic>
#include <chrono>
#include <thread>
#include <vector>

namespace talus {
namespace background_writer_test {
namespace {

TEST(BackgroundWriter, RunsOneJobAtATimeInTheOrderStarted) {
  std::vector<int> order;  // written only by the jobs: safe only if they never overlap
  std::atomic<int> running{0}, overlaps{0};
  BackgroundWriter writer;
  EXPECT_FALSE(writer.pending());
  for (int i = 0; i < 4; ++i) {
    writer.start([&, i] {
      if (running.fetch_add(1) != 0) ++overlaps;
      std::this_thread::sleep_for(std::chrono::milliseconds(5));
      order.push_back(i);
      running.fetch_sub(1);
    });
    EXPECT_TRUE(writer.pending());
  }
  writer.wait();
  EXPECT_FALSE(writer.pending());
  EXPECT_EQ(overlaps.load(), 0);
  EXPECT_EQ(order, (std::vector<int>{0, 1, 2, 3}));
}

TEST(BackgroundWriter, TheCallerGoesOnWhileTheJobRuns) {
  std::atomic<bool> release{false}, done{false};
  BackgroundWriter writer;
  writer.start([&] {
    while (!release.load()) std::this_thread::yield();
    done = true;
  });
  EXPECT_FALSE(done.load());  // start() returned while the job still waits for the caller
  release = true;
  writer.wait();
  EXPECT_TRUE(done.load());
}

TEST(BackgroundWriter, AJobsErrorIsThrownByTheNextWaitOnce) {
  BackgroundWriter writer;
  writer.start([] { throw io_error("cannot write particle frame frames/particles_000003.vtu"); });
  try {
    writer.wait();
    FAIL() << "no error";
  } catch (const Error& e) {
    EXPECT_EQ(e.kind(), Error::Kind::Io);
    EXPECT_STREQ(e.what(), "cannot write particle frame frames/particles_000003.vtu");
  }
  EXPECT_NO_THROW(writer.wait());  // reported once
}

TEST(BackgroundWriter, AFailedJobStopsTheNextFromStarting) {
  BackgroundWriter writer;
  bool second_ran = false;
  writer.start([] { throw io_error("disk full"); });
  EXPECT_THROW(writer.start([&] { second_ran = true; }), Error);
  writer.wait();
  EXPECT_FALSE(second_ran);
}

TEST(BackgroundWriter, TheDestructorWaitsForTheJob) {
  std::atomic<bool> done{false};
  {
    BackgroundWriter writer;
    writer.start([&] {
      std::this_thread::sleep_for(std::chrono::milliseconds(20));
      done = true;
    });
  }
  EXPECT_TRUE(done.load());
  {
    BackgroundWriter writer;  // and drops an error no one waited for, without throwing
    writer.start([] { throw io_error("never reported"); });
  }
}

}  // namespace
}  // namespace background_writer_test
}  // namespace talus
