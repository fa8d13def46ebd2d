#pragma once
// The task scheduler is injected: long-running code takes an Executor so tests
// can run it inline and deterministically, and the app can size it to the cores.
#include <cstddef>
#include <functional>
#include <memory>

namespace relief {

class Executor {
 public:
  virtual ~Executor() = default;
  // Calls body(i) for every i in [0, count), in any order, and returns when all
  // calls have returned. body must be safe to call concurrently.
  virtual void parallel_for(size_t count, const std::function<void(size_t)>& body) = 0;
  virtual unsigned concurrency() const = 0;
};

// Runs everything on the calling thread, in index order.
class InlineExecutor final : public Executor {
 public:
  void parallel_for(size_t count, const std::function<void(size_t)>& body) override;
  unsigned concurrency() const override { return 1; }
};

// Runs on `threads` OS threads (0 = one per hardware core), handing out indices
// in increasing order so neighbouring work items run close together in time.
class ThreadExecutor final : public Executor {
 public:
  explicit ThreadExecutor(unsigned threads = 0);
  void parallel_for(size_t count, const std::function<void(size_t)>& body) override;
  unsigned concurrency() const override { return threads_; }

 private:
  unsigned threads_;
};

// Keeps its threads between calls, waiting (the calling thread is one of
// them): for work split every frame, where starting threads each time would
// cost a frame's page faults and start-up (on this project's virtual
// machines a new thread's stack is memory touched for the first time). One
// call at a time.
class PooledExecutor final : public Executor {
 public:
  explicit PooledExecutor(unsigned threads = 0);
  ~PooledExecutor() override;
  PooledExecutor(const PooledExecutor&) = delete;
  PooledExecutor& operator=(const PooledExecutor&) = delete;
  void parallel_for(size_t count, const std::function<void(size_t)>& body) override;
  unsigned concurrency() const override;

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace relief
