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
  std::exception_ptr first_error;
  std::mutex error_mutex;
  std::vector<std::thread> pool;
  pool.reserve(workers);
  for (std::size_t w = 0; w < workers; ++w) {
    const std::size_t begin = n * w / workers;
    const std::size_t end = n * (w + 1) / workers;
    pool.emplace_back([&, begin, end] {
      try {
        if (thread_init) thread_init();
        body(begin, end);
      } catch (...) {
        std::lock_guard<std::mutex> lock(error_mutex);
        if (!first_error) first_error = std::current_exception();
      }
    });
  }
  for (auto& t : pool) t.join();
  if (first_error) std::rethrow_exception(first_error);
}

}  // namespace mgn
