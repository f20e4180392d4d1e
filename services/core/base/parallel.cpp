#include "core/base/parallel.hpp"

#include <sys/resource.h>
#include <sys/syscall.h>
#include <unistd.h>

#include <algorithm>
#include <atomic>
#include <cerrno>
#include <cstdlib>
#include <exception>
#include <mutex>
#include <stdexcept>
#include <string>
#include <thread>
#include <vector>

namespace pbnbv {

namespace {

int machine_workers() {
  static const int n = [] {
    if (const char* env = std::getenv("PBNBV_THREADS")) {
      const int v = std::atoi(env);
      if (v > 0) return v;
    }
    return std::max(1, static_cast<int>(std::thread::hardware_concurrency()));
  }();
  return n;
}

}  // namespace

int worker_count(std::size_t items, std::size_t min_items_per_worker, int max_workers) {
  const std::size_t per = std::max<std::size_t>(1, min_items_per_worker);
  const std::size_t by_items = std::max<std::size_t>(1, items / per);
  int n = static_cast<int>(std::min<std::size_t>(by_items, static_cast<std::size_t>(machine_workers())));
  if (max_workers > 0) n = std::min(n, max_workers);
  return std::max(1, n);
}

void parallel_run(int workers, const std::function<void(int, int)>& body) {
  workers = std::max(1, workers);
  if (workers == 1) {
    body(0, 1);
    return;
  }
  std::exception_ptr first;
  std::mutex mutex;
  auto guarded = [&](int w) {
    try {
      body(w, workers);
    } catch (...) {
      std::lock_guard<std::mutex> lock(mutex);
      if (!first) first = std::current_exception();
    }
  };
  std::vector<std::thread> threads;
  threads.reserve(workers - 1);
  for (int w = 1; w < workers; ++w) threads.emplace_back(guarded, w);
  guarded(0);
  for (auto& t : threads) t.join();
  if (first) std::rethrow_exception(first);
}

void parallel_for(std::size_t n, const std::function<void(std::size_t, std::size_t, int)>& body,
                  std::size_t grain, int max_workers) {
  if (n == 0) return;
  grain = std::max<std::size_t>(1, grain);
  const int workers = worker_count(n, grain, max_workers);
  if (workers == 1) {
    body(0, n, 0);
    return;
  }
  // Chunks small enough to balance uneven work (about 4 per worker), never below the grain.
  const std::size_t chunk = std::max(grain, (n + 4 * workers - 1) / (4 * workers));
  std::atomic<std::size_t> next{0};
  std::atomic<bool> failed{false};
  parallel_run(workers, [&](int w, int) {
    while (!failed.load(std::memory_order_relaxed)) {
      const std::size_t begin = next.fetch_add(chunk);
      if (begin >= n) return;
      try {
        body(begin, std::min(n, begin + chunk), w);
      } catch (...) {
        failed = true;  // the others stop taking chunks
        throw;
      }
    }
  });
}

int lower_thread_priority(int nice) {
  if (nice < 1 || nice > 19) throw std::invalid_argument("lower_thread_priority: nice " + std::to_string(nice) + " is not in 1 .. 19");
  // PRIO_PROCESS with a thread id: that thread alone (Linux; glibc's gettid wrapper is newer than
  // some of the systems this builds on, the system call is not).
  const auto tid = static_cast<id_t>(::syscall(SYS_gettid));
  errno = 0;
  const int now = ::getpriority(PRIO_PROCESS, tid);
  if (errno == 0 && now < nice) ::setpriority(PRIO_PROCESS, tid, nice);  // refused: it stays as it was
  errno = 0;
  const int after = ::getpriority(PRIO_PROCESS, tid);
  return errno == 0 ? after : now;
}

}  // namespace pbnbv
