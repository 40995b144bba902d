#pragma once
/// @file parallel.hpp  Explicit, deterministic data parallelism.
///
/// Work is split into contiguous index ranges; each item's result depends only on its index, so
/// results are identical for any thread count.

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

}  // namespace mgn
