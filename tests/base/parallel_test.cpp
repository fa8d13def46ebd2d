// The executors of base/parallel.h: every index once, the calling thread
// among the workers, and a pool that keeps its threads between calls.
#include <gtest/gtest.h>

#include <atomic>
#include <mutex>
#include <set>
#include <thread>
#include <vector>

#include "relief/base/parallel.h"

namespace relief {
namespace {

TEST(PooledExecutor, RunsEveryIndexOnceCallAfterCall) {
  PooledExecutor pool(3);
  EXPECT_EQ(pool.concurrency(), 3u);
  for (size_t count : {0u, 1u, 2u, 3u, 7u, 100u}) {
    for (int call = 0; call < 20; ++call) {
      std::vector<std::atomic<int>> seen(count);
      pool.parallel_for(count, [&](size_t i) { seen[i].fetch_add(1); });
      for (size_t i = 0; i < count; ++i) ASSERT_EQ(seen[i].load(), 1) << count << " " << i;
    }
  }
}

TEST(PooledExecutor, KeepsItsThreadsAndRunsThemTogether) {
  PooledExecutor pool(2);
  std::mutex mutex;
  std::set<std::thread::id> threads;
  for (int call = 0; call < 50; ++call) {
    // Each body waits for the other: they can only finish on two threads at once.
    std::atomic<int> arrived{0};
    pool.parallel_for(2, [&](size_t) {
      arrived.fetch_add(1);
      while (arrived.load() < 2) std::this_thread::yield();
      std::lock_guard lock(mutex);
      threads.insert(std::this_thread::get_id());
    });
  }
  EXPECT_EQ(threads.size(), 2u);  // the caller and the one kept thread, every call
  EXPECT_TRUE(threads.contains(std::this_thread::get_id()));
}

TEST(PooledExecutor, OneThreadIsTheCaller) {
  PooledExecutor pool(1);
  std::vector<std::thread::id> ids;
  pool.parallel_for(4, [&](size_t) { ids.push_back(std::this_thread::get_id()); });
  ASSERT_EQ(ids.size(), 4u);
  for (const auto& id : ids) EXPECT_EQ(id, std::this_thread::get_id());
}

}  // namespace
}  // namespace relief
