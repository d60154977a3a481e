#pragma once
// A minimal task runner: a fixed set of independent tasks over the machine's cores, results in
// place. No pool that outlives the call: the tasks here (folds, candidate models) take tens of
// milliseconds to seconds, so a thread's start-up (~50 µs) does not count.
#include <algorithm>
#include <atomic>
#include <cstddef>
#include <exception>
#include <thread>
#include <vector>

namespace hil::parallel {

/// `requested` workers if positive, else the machine's cores; never more than `tasks`, at least 1.
inline std::size_t worker_count(std::size_t tasks, int requested) {
  const std::size_t want = requested > 0 ? static_cast<std::size_t>(requested) : std::max(1u, std::thread::hardware_concurrency());
  return std::max<std::size_t>(1, std::min(tasks, want));
}

/// Runs task(i, worker) for every i < n on `workers` threads (worker 0 is the caller's), each
/// worker taking the next task not yet taken. Every task writes only its own results, so the
/// outcome does not depend on the schedule. Rethrows the exception of the lowest failed task.
template <class Task>
void run_tasks(std::size_t n, std::size_t workers, Task&& task) {
  std::vector<std::exception_ptr> failed(n);
  std::atomic<std::size_t> next{0};
  auto work = [&](std::size_t w) {
    for (std::size_t i = next.fetch_add(1); i < n; i = next.fetch_add(1)) {
      try {
        task(i, w);
      } catch (...) {
        failed[i] = std::current_exception();
      }
    }
  };
  std::vector<std::thread> pool;
  for (std::size_t w = 1; w < workers; ++w) pool.emplace_back(work, w);
  work(0);
  for (auto& t : pool) t.join();
  for (const auto& e : failed)
    if (e) std::rethrow_exception(e);
}

}  // namespace hil::parallel
