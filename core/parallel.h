// Work spread over a few threads: items are taken in order from a shared
// counter, so a slow item does not hold up the others.
#pragma once

#include <algorithm>
#include <atomic>
#include <cstddef>
#include <thread>
#include <vector>

namespace hairrig {

// The one thread-count policy of every `threads` option: a positive request
// as it is, anything else one thread per core the machine reports (at least 1).
inline int ResolveThreads(int requested) {
  if (requested > 0) return requested;
  return std::max(1, static_cast<int>(std::thread::hardware_concurrency()));
}

// Calls make_worker() once per thread (at most `threads`, at least 1; the
// caller's thread is one of them) and the worker it returns with every index
// in [0, count) exactly once. Per-thread state (a detector, a buffer) lives in
// the worker. The worker must not throw.
template <typename MakeWorker>
void ParallelFor(size_t count, int threads, MakeWorker make_worker) {
  std::atomic<size_t> next{0};
  auto run = [&] {
    auto worker = make_worker();
    for (size_t i = next++; i < count; i = next++) worker(i);
  };
  std::vector<std::thread> pool;
  const size_t extra =
      std::min(count, static_cast<size_t>(std::max(1, threads))) - (count > 0 ? 1 : 0);
  for (size_t t = 0; t < extra; ++t) pool.emplace_back(run);
  run();
  for (std::thread& thread : pool) thread.join();
}

}  // namespace hairrig
