// The disk cache of remote stores: hits skip the upstream, the byte budget
// holds, damaged files heal, concurrent requests share one fetch, and the
// cache survives a restart. The upstream is the real local store, wrapped to
// count requests and to hold them until the test lets them through.
#include <gtest/gtest.h>

#include <atomic>
#include <chrono>
#include <condition_variable>
#include <fstream>
#include <mutex>
#include <thread>

#include "relief/net/disk_cache.h"
#include "relief/tiles/store.h"
#include "relief/tiles/store_layout.h"
#include "test_support.h"

namespace relief::testing {
namespace {
namespace fs = std::filesystem;

class CountingSource : public tiles::StoreSource {
 public:
  explicit CountingSource(fs::path root) : inner_(tiles::local_source(root)) {}
  std::string name() const override { return inner_->name(); }
  Result<std::vector<std::byte>> fetch(const std::string& rel) const override {
    ++requests;
    std::unique_lock lock(mutex_);
    opened_.wait(lock, [&] { return open_; });
    return inner_->fetch(rel);
  }
  // While closed, fetches wait.
  void set_open(bool open) {
    {
      std::lock_guard lock(mutex_);
      open_ = open;
    }
    opened_.notify_all();
  }
  mutable std::atomic<int> requests{0};

 private:
  std::shared_ptr<const tiles::StoreSource> inner_;
  mutable std::mutex mutex_;
  mutable std::condition_variable opened_;
  bool open_ = true;
};

// Waits (in real time, only as a safety net) until `done` holds.
template <typename F>
bool eventually(F done) {
  for (int i = 0; i < 60000 && !done(); ++i)
    std::this_thread::sleep_for(std::chrono::milliseconds(1));
  return done();
}

uint64_t bytes_under(const fs::path& dir) {
  uint64_t total = 0;
  for (const auto& e : fs::recursive_directory_iterator(dir)) {
    if (e.is_regular_file()) total += e.file_size();
  }
  return total;
}

class DiskCacheTest : public SmallStoreSuite {
 protected:
  static std::vector<std::string> tile_paths() {
    auto s = tiles::Store::open(store());
    std::vector<std::string> out;
    for (const auto& e : s->index(s->manifest().max_level).entries())
      out.push_back(tiles::tile_relative_path(e.key));
    return out;
  }
};

TEST_F(DiskCacheTest, HitsBudgetRepairAndRestart) {
  ScratchDir cache_dir("disk_cache_dir");
  auto upstream = std::make_shared<CountingSource>(store());
  const auto paths = tile_paths();
  ASSERT_GT(paths.size(), 10u);
  uint64_t largest = 0;
  for (const auto& p : paths) largest = std::max<uint64_t>(largest, fs::file_size(store() / p));
  const uint64_t budget = largest * 4;
  {
    auto cache = net::DiskCache::create(upstream, cache_dir.path(), budget);
    ASSERT_TRUE(cache);
    EXPECT_EQ(upstream->requests, 1);  // the manifest, which keys the cache
    auto first = (*cache)->fetch(paths[0]);
    auto again = (*cache)->fetch(paths[0]);
    ASSERT_TRUE(first && again);
    EXPECT_EQ(*first, *again);
    EXPECT_EQ(upstream->requests, 2);
    EXPECT_EQ((*cache)->stats().hits, 1u);
    // The budget holds while many files pass through.
    for (const auto& p : paths) {
      ASSERT_TRUE((*cache)->fetch(p));
      ASSERT_LE(bytes_under(cache_dir.path()), budget) << p;
      ASSERT_EQ((*cache)->stats().bytes, bytes_under(cache_dir.path()));
    }
    EXPECT_GT((*cache)->stats().evictions, 0u);
    // A damaged cached file is detected and fetched anew.
    const std::string last = paths.back();
    {
      std::fstream f((*cache)->store_directory() / last,
                     std::ios::in | std::ios::out | std::ios::binary);
      f.seekp(-1, std::ios::end);
      f.put('\x7f');
    }
    const int before = upstream->requests;
    auto healed = (*cache)->fetch(last);
    ASSERT_TRUE(healed);
    EXPECT_EQ(upstream->requests, before + 1);
    EXPECT_EQ((*cache)->stats().repaired, 1u);
    EXPECT_TRUE(tiles::StoreSource::verify(last, *healed));
  }
  // A new cache over the same directory starts with what is there (only the
  // manifest is fetched anew).
  const int before = upstream->requests;
  auto reopened = net::DiskCache::create(upstream, cache_dir.path(), budget);
  ASSERT_TRUE((*reopened)->fetch(paths.back()));
  EXPECT_EQ(upstream->requests, before + 1);
  EXPECT_EQ((*reopened)->stats().hits, 1u);
}

TEST_F(DiskCacheTest, ConcurrentRequestsShareOneFetch) {
  ScratchDir cache_dir("disk_cache_shared");
  auto upstream = std::make_shared<CountingSource>(store());
  auto cache = net::DiskCache::create(upstream, cache_dir.path(), uint64_t{64} << 20);
  ASSERT_TRUE(cache);
  const int before = upstream->requests;
  const std::string path = tile_paths()[3];
  upstream->set_open(false);  // the first fetch stays in flight until all have asked
  std::vector<std::thread> threads;
  std::atomic<int> good{0};
  for (int i = 0; i < 8; ++i) {
    threads.emplace_back([&] {
      if ((*cache)->fetch(path)) ++good;
    });
  }
  const bool all_asked = eventually([&] { return (*cache)->stats().shared == 7; });
  upstream->set_open(true);
  for (auto& t : threads) t.join();
  ASSERT_TRUE(all_asked);
  EXPECT_EQ(good.load(), 8);
  EXPECT_EQ(upstream->requests, before + 1);  // the seven others waited for the one in flight
  EXPECT_EQ((*cache)->stats().shared, 7u);
}

TEST_F(DiskCacheTest, AStoreReadsThroughTheCache) {
  ScratchDir cache_dir("disk_cache_store");
  auto upstream = std::make_shared<CountingSource>(store());
  auto cache = net::DiskCache::create(upstream, cache_dir.path(), uint64_t{256} << 20);
  std::shared_ptr<const tiles::StoreSource> source = *cache;
  auto cached = tiles::Store::open(source);
  ASSERT_TRUE(cached) << cached.error().message;
  auto local = tiles::Store::open(store());
  const auto key = local->index(local->manifest().max_level).entries().front().key;
  EXPECT_EQ(cached->read_tile(key)->raster.bytes().size(),
            local->read_tile(key)->raster.bytes().size());
  const int before = upstream->requests;
  auto again = tiles::Store::open(source);  // manifest and indices now from disk
  ASSERT_TRUE(again);
  EXPECT_EQ(upstream->requests, before);
}

}  // namespace
}  // namespace relief::testing
