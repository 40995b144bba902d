#include <mgn/core/error.hpp>
#include <mgn/core/parallel.hpp>

#include <algorithm>
#include <exception>
#include <mutex>
#include <thread>
#include <vector>

namespace mgn {

int resolve_num_threads(int requested) {
  if (requested < 0) {
    throw_error<InvalidArgument>("num_threads must be >= 0 (0 = all hardware threads), got ",
                                 requested);
  }
  if (requested > 0) return requested;
  const unsigned hw = std::thread::hardware_concurrency();
  return hw == 0 ? 1 : static_cast<int>(hw);
}

namespace {

/// Runs work(w) on `workers` threads (w = 0 .. workers-1) and joins them; the first exception is
/// re-thrown after the join. `on_error` (may be empty) runs once per failing worker, under the
/// error lock, e.g. to stop a shared queue.
void run_workers(std::size_t workers, const std::function<void(std::size_t)>& work,
                 const std::function<void()>& on_error = {}) {
  std::exception_ptr first_error;
  std::mutex error_mutex;
  std::vector<std::thread> pool;
  pool.reserve(workers);
  for (std::size_t w = 0; w < workers; ++w) {
    pool.emplace_back([&, w] {
      try {
        work(w);
      } catch (...) {
        std::lock_guard<std::mutex> lock(error_mutex);
        if (!first_error) first_error = std::current_exception();
        if (on_error) on_error();
      }
    });
  }
  for (auto& t : pool) t.join();
  if (first_error) std::rethrow_exception(first_error);
}

}  // namespace

void parallel_for(std::size_t n, int num_threads, std::size_t min_chunk,
                  const std::function<void(std::size_t, std::size_t)>& body,
                  const std::function<void()>& thread_init) {
  if (n == 0) return;
  const std::size_t threads = static_cast<std::size_t>(resolve_num_threads(num_threads));
  const std::size_t chunk_min = std::max<std::size_t>(1, min_chunk);
  const std::size_t max_chunks = (n + chunk_min - 1) / chunk_min;
  const std::size_t workers = std::min(threads, max_chunks);
  if (workers <= 1) {
    if (thread_init) thread_init();
    body(0, n);
    return;
  }
  // Contiguous, equal ranges: which thread runs a range never changes what is computed.
  run_workers(workers, [&](std::size_t w) {
    if (thread_init) thread_init();
    body(n * w / workers, n * (w + 1) / workers);
  });
}

BlockQueue::BlockQueue(std::size_t n, std::size_t block)
    : n_(n), block_(std::max<std::size_t>(1, block)), num_blocks_((n + block_ - 1) / block_) {}

bool BlockQueue::next(std::size_t& begin, std::size_t& end) {
  if (stopped_.load(std::memory_order_relaxed)) return false;
  const std::size_t k = next_.fetch_add(1, std::memory_order_relaxed);
  if (k >= num_blocks_) return false;
  begin = k * block_;
  end = std::min(n_, begin + block_);
  return true;
}

void parallel_workers_dynamic(std::size_t n, int num_threads, std::size_t block,
                              const std::function<void(BlockQueue&)>& worker) {
  const std::size_t threads = static_cast<std::size_t>(resolve_num_threads(num_threads));
  if (n == 0) return;
  BlockQueue queue(n, block);
  const std::size_t workers = std::min(threads, queue.num_blocks());
  if (workers <= 1) {
    worker(queue);
    return;
  }
  run_workers(
      workers, [&](std::size_t) { worker(queue); }, [&] { queue.stop(); });
}

void parallel_for_dynamic(std::size_t n, int num_threads, std::size_t block,
                          const std::function<void(std::size_t, std::size_t)>& body,
                          const std::function<void()>& thread_init) {
  parallel_workers_dynamic(n, num_threads, block, [&](BlockQueue& queue) {
    if (thread_init) thread_init();
    for (std::size_t b, e; queue.next(b, e);) body(b, e);
  });
}

}  // namespace mgn
