// The one parallel loop: every item exactly once, the caller's thread taking part, and a
// worker's exception reaching the caller.
#include "core/base/parallel.hpp"

#include <gtest/gtest.h>
#include <sys/resource.h>
#include <sys/syscall.h>
#include <unistd.h>

#include <algorithm>
#include <atomic>
#include <cerrno>
#include <stdexcept>
#include <string>
#include <thread>
#include <vector>

using namespace pbnbv;

TEST(Parallel, WorkerCountFollowsItemsGrainAndCap) {
  EXPECT_EQ(worker_count(0), 1);
  EXPECT_EQ(worker_count(1), 1);
  EXPECT_EQ(worker_count(10, 10), 1);    // one worker's share
  EXPECT_EQ(worker_count(1000, 1, 1), 1);
  EXPECT_GE(worker_count(1000, 1), 1);
  EXPECT_LE(worker_count(3, 1), 3);      // never more workers than items
}

TEST(Parallel, ForCoversEveryIndexExactlyOnce) {
  for (std::size_t n : {1u, 7u, 100u, 10007u}) {
    for (std::size_t grain : {1u, 3u, 64u}) {
      std::vector<std::atomic<int>> hits(n);
      parallel_for(n, [&](std::size_t b, std::size_t e, int) {
        ASSERT_LT(b, e);
        for (std::size_t i = b; i < e; ++i) ++hits[i];
      }, grain);
      for (std::size_t i = 0; i < n; ++i) ASSERT_EQ(hits[i].load(), 1) << "n " << n << " grain " << grain << " index " << i;
    }
  }
  parallel_for(0, [](std::size_t, std::size_t, int) { FAIL() << "no work for n = 0"; });
}

TEST(Parallel, RunGivesEachWorkerItsIndexAndTheCallerIsWorkerZero) {
  const std::thread::id caller = std::this_thread::get_id();
  std::vector<int> seen(4, 0);
  std::thread::id zero;
  parallel_run(4, [&](int w, int n) {
    EXPECT_EQ(n, 4);
    seen[w] += 1;
    if (w == 0) zero = std::this_thread::get_id();
  });
  EXPECT_EQ(seen, std::vector<int>({1, 1, 1, 1}));
  EXPECT_EQ(zero, caller);
}

TEST(Parallel, AWorkersExceptionReachesTheCaller) {
  try {
    parallel_run(3, [](int w, int) {
      if (w == 2) throw std::runtime_error("worker 2 failed");
    });
    FAIL() << "expected the worker's exception";
  } catch (const std::runtime_error& e) {
    EXPECT_EQ(std::string(e.what()), "worker 2 failed");
  }
  std::atomic<int> done{0};
  EXPECT_THROW(parallel_for(1000, [&](std::size_t b, std::size_t, int) {
    if (b == 0) throw std::invalid_argument("bad item 0");
    ++done;
  }), std::invalid_argument);
}

namespace {
int thread_nice() {
  errno = 0;
  return ::getpriority(PRIO_PROCESS, static_cast<id_t>(::syscall(SYS_gettid)));
}
}  // namespace

// Lowered on one thread, the priority is that thread's and its children's, never the caller's;
// it is never raised again.
TEST(Parallel, LowerThreadPriorityIsTheThreadsOwnAndInherited) {
  const int caller = thread_nice();
  const int expected = std::max(caller, 7);  // a test run already under nice > 7 stays there
  int lowered = -100, child = -100, again = -100, after_again = -100;
  std::thread t([&] {
    lowered = lower_thread_priority(7);
    std::thread c([&] { child = thread_nice(); });
    c.join();
    again = lower_thread_priority(3);  // not raised back
    after_again = thread_nice();
  });
  t.join();
  EXPECT_EQ(lowered, expected);
  EXPECT_EQ(child, expected);
  EXPECT_EQ(again, expected);
  EXPECT_EQ(after_again, expected);
  EXPECT_EQ(thread_nice(), caller);  // the calling thread is as it was
  EXPECT_THROW(lower_thread_priority(0), std::invalid_argument);
  EXPECT_THROW(lower_thread_priority(20), std::invalid_argument);
}
