// LruCache: eviction order, the byte budget, pins outliving eviction, and
// many threads at once (the tsan preset runs this under ThreadSanitizer).
#include "relief/base/lru_cache.h"

#include <gtest/gtest.h>

#include <atomic>
#include <string>
#include <thread>
#include <vector>

namespace relief {
namespace {

using Cache = LruCache<int, std::string>;
uint64_t size_of(const std::string& s) {
  return s.size();
}
Cache::Ptr value(int key, size_t bytes) {
  return std::make_shared<const std::string>(std::to_string(key) + std::string(bytes, '.'));
}

TEST(LruCache, EvictsLeastRecentlyUsedWithinTheBudget) {
  Cache cache(100, size_of);
  cache.put(1, std::make_shared<const std::string>(40, 'a'));
  cache.put(2, std::make_shared<const std::string>(40, 'b'));
  ASSERT_TRUE(cache.get(1));  // 2 is now the least recently used
  cache.put(3, std::make_shared<const std::string>(40, 'c'));
  EXPECT_TRUE(cache.get(1));
  EXPECT_FALSE(cache.get(2));
  EXPECT_TRUE(cache.get(3));
  EXPECT_EQ(cache.used_bytes(), 80u);
}

TEST(LruCache, AnEvictedValueLivesWhileAReaderHoldsIt) {
  Cache cache(10, size_of);
  cache.put(1, std::make_shared<const std::string>(8, 'a'));
  const Cache::Ptr pinned = cache.get(1);
  cache.put(2, std::make_shared<const std::string>(8, 'b'));
  EXPECT_FALSE(cache.get(1));
  EXPECT_EQ(*pinned, std::string(8, 'a'));
}

TEST(LruCache, ManyThreadsGetAndPutConsistently) {
  constexpr int kKeys = 64, kThreads = 4, kRounds = 4000;
  Cache cache(16 * 100, size_of);  // room for about a quarter of the keys
  std::atomic<int> wrong{0};
  std::vector<std::thread> threads;
  for (int t = 0; t < kThreads; ++t) {
    threads.emplace_back([&, t] {
      for (int i = 0; i < kRounds; ++i) {
        const int key = (i * 7 + t * 13) % kKeys;
        if (auto v = cache.get(key)) {
          if (v->rfind(std::to_string(key), 0) != 0) ++wrong;
        } else {
          cache.put(key, value(key, 96));
        }
        if (cache.used_bytes() > cache.budget_bytes()) ++wrong;
      }
    });
  }
  for (auto& th : threads) th.join();
  EXPECT_EQ(wrong.load(), 0);
  EXPECT_EQ(cache.hits() + cache.misses(), static_cast<uint64_t>(kThreads) * kRounds);
}

}  // namespace
}  // namespace relief
