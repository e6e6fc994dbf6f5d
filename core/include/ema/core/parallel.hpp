// The numerical core's one way to run a loop on worker threads: exceptions carried to the caller.
#pragma once

#include <algorithm>
#include <atomic>
#include <exception>
#include <mutex>
#include <thread>
#include <vector>

namespace ema {

/// Runs `worker(t, stop)` for t = 0 .. threads-1: t = 0 on the calling thread, the others on
/// threads of their own, and returns when all have finished. A worker that throws (a progress
/// callback's `Cancelled`, bad_alloc) raises `stop`, which the others check at each step of their
/// loop to leave it early; the first exception thrown is then rethrown here, on the calling
/// thread, after every thread has been joined: no std::terminate, no thread left running.
/// `worker` takes (int t, const std::atomic<bool>& stop); threads < 1 counts as 1.
template <class Worker>
void RunOnThreads(int threads, Worker&& worker) {
  std::atomic<bool> stop{false};
  std::mutex first_mutex;
  std::exception_ptr first;
  auto guarded = [&](int t) noexcept {
    try {
      worker(t, static_cast<const std::atomic<bool>&>(stop));
    } catch (...) {
      stop.store(true);
      std::lock_guard<std::mutex> lock(first_mutex);
      if (!first) first = std::current_exception();
    }
  };
  std::vector<std::thread> pool;
  pool.reserve(static_cast<std::size_t>(std::max(0, threads - 1)));
  try {
    for (int t = 1; t < threads; ++t) pool.emplace_back(guarded, t);
  } catch (...) {  // no thread to be had: the started ones stop, then the caller hears of it
    stop.store(true);
    for (std::thread& th : pool) th.join();
    throw;
  }
  guarded(0);
  for (std::thread& th : pool) th.join();
  if (first) std::rethrow_exception(first);
}

}  // namespace ema
