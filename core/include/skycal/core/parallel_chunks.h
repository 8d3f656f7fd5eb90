// Splits [0, n) into one contiguous chunk per worker and runs fn(begin, end, worker) on
// std::threads (the calling thread takes the first chunk). Exceptions from any worker are
// rethrown on the caller, the lowest worker's first. Chunks are in worker order, so results
// gathered per worker and concatenated in that order are the serial loop's.
#pragma once
#include <algorithm>
#include <exception>
#include <thread>
#include <vector>

namespace skycal {

// `requested` threads, or the machine's when <= 0.
inline int ResolveThreads(int requested) {
  if (requested > 0) return requested;
  return std::max(1, static_cast<int>(std::thread::hardware_concurrency()));
}

template <class Fn>
void ParallelChunks(int n, int workers, Fn&& fn) {
  workers = std::max(1, std::min(workers, n));
  std::vector<std::exception_ptr> errors(workers);
  auto run = [&](int w) {
    const int begin = static_cast<int>(static_cast<long long>(n) * w / workers);
    const int end = static_cast<int>(static_cast<long long>(n) * (w + 1) / workers);
    try {
      fn(begin, end, w);
    } catch (...) {
      errors[w] = std::current_exception();
    }
  };
  std::vector<std::thread> pool;
  pool.reserve(workers - 1);
  for (int w = 1; w < workers; ++w) pool.emplace_back(run, w);
  run(0);
  for (auto& t : pool) t.join();
  for (auto& e : errors)
    if (e) std::rethrow_exception(e);
}

}  // namespace skycal
