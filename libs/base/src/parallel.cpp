#include "relief/base/parallel.h"

#include <algorithm>
#include <atomic>
#include <thread>
#include <vector>

namespace relief {

void InlineExecutor::parallel_for(size_t count, const std::function<void(size_t)>& body) {
  for (size_t i = 0; i < count; ++i) body(i);
}

ThreadExecutor::ThreadExecutor(unsigned threads)
    : threads_(threads ? threads : std::max(1u, std::thread::hardware_concurrency())) {}

void ThreadExecutor::parallel_for(size_t count, const std::function<void(size_t)>& body) {
  std::atomic<size_t> next{0};
  auto worker = [&] {
    for (size_t i = next.fetch_add(1); i < count; i = next.fetch_add(1)) body(i);
  };
  const size_t n = std::min<size_t>(threads_, count);
  if (n <= 1) {
    worker();
    return;
  }
  std::vector<std::jthread> pool;
  for (size_t t = 1; t < n; ++t) pool.emplace_back(worker);
  worker();
}

}  // namespace relief
