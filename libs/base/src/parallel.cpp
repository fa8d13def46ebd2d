#include "relief/base/parallel.h"

#include <algorithm>
#include <atomic>
#include <cassert>
#include <condition_variable>
#include <cstdint>
#include <mutex>
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

struct PooledExecutor::Impl {
  unsigned threads = 1;
  std::mutex mutex;
  std::condition_variable work, done;
  // The call being run: its body and count, handed out through `next`.
  const std::function<void(size_t)>* body = nullptr;
  size_t count = 0;
  std::atomic<size_t> next{0};
  uint64_t call = 0;     // counts calls: a waiting thread joins each new one
  unsigned running = 0;  // pool threads still in the current call
  bool stopping = false;
  std::vector<std::thread> pool;

  void take_indices() {
    for (size_t i = next.fetch_add(1); i < count; i = next.fetch_add(1)) (*body)(i);
  }

  void serve() {
    uint64_t seen = 0;
    std::unique_lock lock(mutex);
    for (;;) {
      work.wait(lock, [&] { return stopping || call != seen; });
      if (stopping) return;
      seen = call;
      lock.unlock();
      take_indices();
      lock.lock();
      if (--running == 0) done.notify_one();
    }
  }
};

PooledExecutor::PooledExecutor(unsigned threads) : impl_(std::make_unique<Impl>()) {
  impl_->threads = threads ? threads : std::max(1u, std::thread::hardware_concurrency());
  for (unsigned t = 1; t < impl_->threads; ++t)
    impl_->pool.emplace_back([this] { impl_->serve(); });
}

PooledExecutor::~PooledExecutor() {
  {
    std::lock_guard lock(impl_->mutex);
    impl_->stopping = true;
  }
  impl_->work.notify_all();
  for (std::thread& t : impl_->pool) t.join();
}

unsigned PooledExecutor::concurrency() const {
  return impl_->threads;
}

void PooledExecutor::parallel_for(size_t count, const std::function<void(size_t)>& body) {
  Impl& m = *impl_;
  if (m.pool.empty() || count <= 1) {
    for (size_t i = 0; i < count; ++i) body(i);
    return;
  }
  {
    std::lock_guard lock(m.mutex);
    assert(m.running == 0);  // one call at a time
    m.body = &body;
    m.count = count;
    m.next = 0;
    m.running = static_cast<unsigned>(m.pool.size());
    ++m.call;
  }
  m.work.notify_all();
  m.take_indices();
  std::unique_lock lock(m.mutex);
  m.done.wait(lock, [&] { return m.running == 0; });
}

}  // namespace relief
