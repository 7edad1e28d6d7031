#pragma once
// One write at a time on a thread of its own, so that the run loop's output overlaps the steps
// that follow it instead of holding every core idle (docs/performance.md, "Frames written in the
// background"). The particle frames use it: the run loop copies a frame's arrays out of the
// particle store (in parallel), then VTK's compression and the file write run here while the
// solver steps on.
#include <atomic>
#include <exception>
#include <functional>
#include <thread>

namespace talus {

class BackgroundWriter {
 public:
  BackgroundWriter() = default;
  /// Waits for the write in flight; an error it met is dropped here (a destructor cannot report
  /// it): call wait() wherever the outcome matters.
  ~BackgroundWriter();
  BackgroundWriter(const BackgroundWriter&) = delete;
  BackgroundWriter& operator=(const BackgroundWriter&) = delete;

  /// Waits for the write before (throwing its error, if it failed; `job` is then not started), then
  /// runs `job` on a new thread. The job must own or outlive everything it reads.
  void start(std::function<void()> job);
  /// Waits for the write in flight, if any, and throws the exception it ended with.
  void wait();
  /// Whether a write was started and not yet waited for.
  bool pending() const { return thread_.joinable(); }
  /// Whether wait() would return at once: no write in flight, or its job has ended.
  bool idle() const { return !thread_.joinable() || done_.load(std::memory_order_acquire); }

 private:
  std::thread thread_;
  std::atomic<bool> done_{false};
  std::exception_ptr error_;  // set by the job's thread, read after the join
};

}  // namespace talus
