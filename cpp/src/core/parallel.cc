#include "indoorloc/core/parallel.h"

#include <algorithm>
#include <atomic>
#include <chrono>
#include <condition_variable>
#include <exception>
#include <mutex>
#include <thread>
#include <vector>

#include "indoorloc/core/check.h"
#include "indoorloc/core/interrupt.h"

namespace indoorloc {

int ResolveThreadCount(int requested) {
  if (requested > 0) return requested;
  const unsigned hw = std::thread::hardware_concurrency();
  return hw == 0 ? 1 : static_cast<int>(hw);
}

void ParallelForRuns(int n_runs, int n_threads, std::uint64_t seed,
                     const std::function<void(int run, RandomStream& rng)>& fn) {
  CheckArgument(n_runs >= 0, "n_runs", "must be >= 0, got " + std::to_string(n_runs));
  if (n_runs == 0) return;
  const int threads = std::min(ResolveThreadCount(n_threads), n_runs);

  std::atomic<int> next_run{0};
  std::atomic<bool> failed{false};
  std::exception_ptr first_error;
  std::mutex error_mutex;

  auto worker = [&]() {
    while (!failed.load(std::memory_order_relaxed)) {
      const int run = next_run.fetch_add(1);
      if (run >= n_runs) return;
      try {
        CheckInterrupt();  // Ctrl-C between runs (polls the host on its thread)
      } catch (...) {
        std::lock_guard<std::mutex> lock(error_mutex);
        if (!first_error) first_error = std::current_exception();
        failed.store(true);
        return;
      }
      // The stream depends on (seed, run) only: the thread that runs it does not matter.
      RandomStream rng(seed, static_cast<std::uint64_t>(run));
      try {
        fn(run, rng);
      } catch (...) {
        std::lock_guard<std::mutex> lock(error_mutex);
        if (!first_error) first_error = std::current_exception();
        failed.store(true);
      }
    }
  };

  if (threads == 1) {
    worker();
  } else {
    std::vector<std::thread> pool;
    pool.reserve(static_cast<size_t>(threads));
    std::mutex done_mutex;
    std::condition_variable done_cv;
    int done = 0;
    for (int t = 0; t < threads; ++t) {
      pool.emplace_back([&] {
        worker();
        std::lock_guard<std::mutex> lock(done_mutex);
        ++done;
        done_cv.notify_one();
      });
    }
    // The calling thread (Python's main thread) waits polling for Ctrl-C; a stop makes the
    // workers' CheckInterrupt throw, so they finish their current step and return.
    {
      std::unique_lock<std::mutex> lock(done_mutex);
      while (done < threads) {
        if (!done_cv.wait_for(lock, std::chrono::milliseconds(20), [&] { return done == threads; })) {
          lock.unlock();
          PollInterrupt();
          lock.lock();
        }
      }
    }
    for (std::thread& t : pool) t.join();
    // A stop this thread saw after the workers' last check (they finished their runs without
    // another one) must not outlive the call: left pending, it would interrupt the next call
    // with this call's KeyboardInterrupt (seen as a stale alarm in the property suite). Honour
    // it here; the user asked to stop, so it wins over a worker's error.
    if (PollInterrupt()) throw Interrupted();
  }
  if (first_error) std::rethrow_exception(first_error);
}

}  // namespace indoorloc
