// Image rows shared out to worker threads: the reference's per-pixel loops (shadow and reflection
// references) hand rows out through one atomic counter, so results do not depend on the thread
// count (each pixel's work is seeded by its index).
#pragma once

#include <algorithm>
#include <chrono>
#include <thread>
#include <vector>

namespace kaskad::reference {

/// Runs `worker` on min(rows, threads) threads (threads <= 0: the hardware's count), the calling
/// thread included, and returns when all have finished: the wall time in seconds. `worker` takes
/// rows from a shared counter until none are left.
template <class Worker>
double run_row_workers(int rows, int threads, Worker&& worker) {
  const unsigned hw = std::max(1u, std::thread::hardware_concurrency());
  const int count = std::max(1, std::min(rows, threads > 0 ? threads : int(hw)));
  const auto start = std::chrono::steady_clock::now();
  {  // the pool joins at the end of this block
    std::vector<std::jthread> pool;
    for (int i = 1; i < count; ++i) pool.emplace_back(worker);
    worker();  // the calling thread works too
  }
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
}

}  // namespace kaskad::reference
