#pragma once
// One way to run work on several cores, with one thread policy for the whole program:
//   - workers = the cores of the machine (std::thread::hardware_concurrency), or the
//     environment variable PBNBV_THREADS when it is set to a positive number (benchmarks, a
//     shared machine), never more than there are items, never more than a caller's cap;
//   - the calling thread is worker 0, the others are started for the call and joined before it
//     returns (no pool, no global state);
//   - an exception thrown by any worker reaches the caller: the first one is rethrown after
//     every worker has stopped, never std::terminate.
#include <cstddef>
#include <functional>

namespace pbnbv {

// Workers for `items` pieces of work when each should get at least `min_items_per_worker`
// (>= 1), capped at `max_workers` (0: no cap). Always >= 1.
int worker_count(std::size_t items, std::size_t min_items_per_worker = 1, int max_workers = 0);

// Runs body(worker, workers) for worker = 0 .. workers - 1 concurrently (worker 0 on the
// calling thread) and returns when all have finished. For callers that split the work
// themselves (interleaved rows, one scratch buffer per worker).
void parallel_run(int workers, const std::function<void(int worker, int workers)>& body);

// Runs body(begin, end, worker) over [0, n) in contiguous chunks of at least `grain` items,
// handed out dynamically (a worker that finishes early takes the next chunk), on at most
// `max_workers` workers (0: the policy above). The chunks cover [0, n) exactly once.
void parallel_for(std::size_t n, const std::function<void(std::size_t begin, std::size_t end, int worker)>& body,
                  std::size_t grain = 1, int max_workers = 0);

// Work that may wait for the CPU: lowers the calling thread's scheduling priority to the nice
// value `nice` (1 .. 19; on Linux a thread's nice value is its own, and the threads it starts,
// parallel_run's workers among them, inherit it). Whatever else runs at the normal priority on a
// busy machine gets the cores first; an idle core still runs this at full speed. Never raises a
// priority (that needs privileges). Returns the calling thread's nice value afterwards.
int lower_thread_priority(int nice);

}  // namespace pbnbv
