#pragma once
/// @file parallel.hpp  Explicit, deterministic data parallelism.
///
/// Work is split into index ranges; each item's result depends only on its index, so results are
/// identical for any thread count. parallel_for() gives every thread one contiguous range (items
/// of similar cost); parallel_for_dynamic() and parallel_workers_dynamic() hand out small blocks
/// from a shared counter (items whose cost varies, so that a slow item does not leave the other
/// threads idle while it runs).

#include <atomic>
#include <cstddef>
#include <functional>

namespace mgn {

/// Number of threads for a batch call. 0 means "all hardware threads".
struct ParallelOptions {
  int num_threads = 0;
};

/// Resolves a user thread count: 0 -> hardware concurrency (at least 1); negative is an error.
int resolve_num_threads(int requested);

/// Calls body(begin, end) over contiguous chunks of [0, n) on up to num_threads threads
/// (0 = all). Chunks have at least `min_chunk` items. Runs inline for a single chunk. The first
/// exception thrown by any chunk is re-thrown in the caller after all threads have joined.
/// `thread_init` (may be empty) runs once at the start of every worker, e.g. to set FTZ/DAZ.
void parallel_for(std::size_t n, int num_threads, std::size_t min_chunk,
                  const std::function<void(std::size_t, std::size_t)>& body,
                  const std::function<void()>& thread_init = {});

/// The blocks of one parallel_workers_dynamic() call, shared by its workers: block k is the
/// index range [k·block, min(n, (k+1)·block)). Blocks are handed out once each, in increasing
/// k (which worker gets which one depends on timing).
class BlockQueue {
 public:
  BlockQueue(std::size_t n, std::size_t block);
  BlockQueue(const BlockQueue&) = delete;
  BlockQueue& operator=(const BlockQueue&) = delete;

  /// Takes the next block into [begin, end) and returns true; returns false (leaving begin and
  /// end unchanged) when every block has been handed out or after stop().
  bool next(std::size_t& begin, std::size_t& end);
  /// Hands out no further block (blocks already taken are not interrupted).
  void stop() { stopped_.store(true, std::memory_order_relaxed); }
  /// Whether stop() was called (by a failing worker): a worker in a long block may end early.
  bool stopped() const { return stopped_.load(std::memory_order_relaxed); }

  std::size_t num_blocks() const { return num_blocks_; }

 private:
  std::size_t n_, block_, num_blocks_;
  std::atomic<std::size_t> next_{0};
  std::atomic<bool> stopped_{false};
};

/// Dynamic scheduling with per-thread state: calls worker(queue) once on each of
/// min(threads, number of blocks) threads, where threads = resolve_num_threads(num_threads)
/// (0 = all hardware threads, negative -> InvalidArgument), and each worker takes blocks of
/// `block` items (0 is taken as 1) from the shared `queue` until it is empty:
///
///     parallel_workers_dynamic(n, num_threads, 8, [&](BlockQueue& q) {
///       State s;  // made once per thread
///       for (std::size_t b, e; q.next(b, e);) for (std::size_t i = b; i < e; ++i) run(s, i);
///     });
///
/// A worker may get no block at all (others took them first). Nothing runs for n == 0; a single
/// worker runs inline on the calling thread. Every item is processed exactly once, by whichever
/// thread takes its block, so the results are the same for any thread count only if each item
/// writes its own slots (by index) and does not depend on the items before it on its thread.
/// Exceptions: the first exception thrown by a worker is re-thrown in the caller after every
/// thread has joined (later ones are dropped); once a worker has thrown, the queue hands out no
/// further block, so the other workers end after the block they are in.
void parallel_workers_dynamic(std::size_t n, int num_threads, std::size_t block,
                              const std::function<void(BlockQueue&)>& worker);

/// Dynamic scheduling without per-thread state: calls body(begin, end) for every block
/// [k·block, min(n, (k+1)·block)) of [0, n), blocks taken from a shared counter in increasing k
/// by min(threads, blocks) threads (see parallel_workers_dynamic() for num_threads, `block`,
/// the order and the exceptions). `thread_init` (may be empty) runs once at the start of every
/// worker, as in parallel_for().
void parallel_for_dynamic(std::size_t n, int num_threads, std::size_t block,
                          const std::function<void(std::size_t, std::size_t)>& body,
                          const std::function<void()>& thread_init = {});

}  // namespace mgn
