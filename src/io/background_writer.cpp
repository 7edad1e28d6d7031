#include "talus/io/background_writer.hpp"

#include <omp.h>
#include <pthread.h>
#include <sched.h>
#include <signal.h>

#include <utility>
#include <vector>

namespace talus {

namespace {

/// A thread started from a bound OpenMP thread (OMP_PROC_BIND, or OMP_PLACES set) inherits its
/// place: the writer would then share the run loop's core while the other cores wait, and a frame
/// written "in the background" would cost as much as one written in the foreground (measured: the
/// h = 0.005 m flume on 1 thread, no gain). So the writer may run on every CPU of every OpenMP
/// place: the CPUs the run was given (a taskset or a cgroup limits the places too).
void allow_every_openmp_place() {
  if (omp_get_proc_bind() == omp_proc_bind_false || omp_get_num_places() <= 0) return;
  cpu_set_t cpus;
  CPU_ZERO(&cpus);
  for (int place = 0; place < omp_get_num_places(); ++place) {
    std::vector<int> ids(static_cast<std::size_t>(omp_get_place_num_procs(place)));
    omp_get_place_proc_ids(place, ids.data());
    for (int id : ids)
      if (id >= 0 && id < CPU_SETSIZE) CPU_SET(id, &cpus);
  }
  if (CPU_COUNT(&cpus) > 0) pthread_setaffinity_np(pthread_self(), sizeof cpus, &cpus);  // best effort
}

}  // namespace

BackgroundWriter::~BackgroundWriter() {
  if (thread_.joinable()) thread_.join();
}

void BackgroundWriter::start(std::function<void()> job) {
  wait();
  done_.store(false, std::memory_order_relaxed);
  thread_ = std::thread([this, job = std::move(job)] {
    // Signals go to the run loop's thread: SIGINT and SIGTERM set its flag for a checkpoint, and
    // a file write here is never interrupted by one.
    sigset_t all;
    sigfillset(&all);
    pthread_sigmask(SIG_BLOCK, &all, nullptr);
    allow_every_openmp_place();
    try {
      job();
    } catch (...) {
      error_ = std::current_exception();  // handed to the run loop's thread by wait()
    }
    done_.store(true, std::memory_order_release);
  });
}

void BackgroundWriter::wait() {
  if (thread_.joinable()) thread_.join();
  if (error_) std::rethrow_exception(std::exchange(error_, nullptr));
}

}  // namespace talus
