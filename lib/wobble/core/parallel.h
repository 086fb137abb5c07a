// Independent work items on a pool of threads: synthesis trials (synth/anneal.cc), batched
// rollouts (python/). Each item writes its own result slot, so the order in which threads take
// items never changes a result: N threads give the same answer as one, bit for bit.
#pragma once

#include <algorithm>
#include <atomic>
#include <cstddef>
#include <exception>
#include <mutex>
#include <thread>
#include <vector>

namespace wobble {

// The number of threads `threads` asks for: 0 or less means every core.
inline int ResolveThreads(int threads) {
  return threads > 0 ? threads : int(std::max(1u, std::thread::hardware_concurrency()));
}

// Calls item(i) for i in [0, n) on ResolveThreads(threads) threads (no more than n), taking
// items in turn. The first exception an item throws is rethrown here once every thread has
// stopped; the items not yet started then are skipped.
template <class F> void ParallelFor(size_t n, int threads, F&& item) {
  const size_t pool_size = std::min<size_t>(size_t(ResolveThreads(threads)), n);
  if (pool_size <= 1) {
    for (size_t i = 0; i < n; ++i) item(i);
    return;
  }
  std::atomic<size_t> next{0};
  std::exception_ptr first_error;
  std::mutex error_mutex;
  auto work = [&] {
    for (size_t i; (i = next.fetch_add(1)) < n;) {
      try {
        item(i);
      } catch (...) {
        std::lock_guard<std::mutex> lock(error_mutex);
        if (!first_error) first_error = std::current_exception();
        next = n;  // the others stop after their current item
      }
    }
  };
  std::vector<std::thread> pool;
  pool.reserve(pool_size - 1);
  for (size_t t = 1; t < pool_size; ++t) pool.emplace_back(work);
  work();  // the calling thread is one of the pool
  for (std::thread& th : pool) th.join();
  if (first_error) std::rethrow_exception(first_error);
}

}  // namespace wobble
