// One disk cache directory, several stores: each store served by `relief
// serve` on loopback reads its own data through the cache, a store rebuilt at
// the same URL is not served stale, and the last store seen at a URL still
// reads offline.
#include <gtest/gtest.h>

#include <signal.h>
#include <sys/wait.h>

#include "relief/net/disk_cache.h"
#include "relief/net/http_source.h"
#include "relief/tiles/store.h"
#include "servers.h"
#include "test_support.h"

namespace relief::testing {
namespace {
namespace fs = std::filesystem;

class CacheIdentityTest : public SmallStoreSuite {
 protected:
  static void SetUpTestSuite() {
    SmallStoreSuite::SetUpTestSuite();
    other_ = scratch() / "other";
    ASSERT_EQ(run_relief({"build", data("srtm/N41E001.hgt.zip"), "--kind", "elevation", "-o",
                          other_.string(), "-q"})
                  .exit_code,
              0);
  }
  // The N41E001 store, beside SmallStoreSuite's N42E001.
  static const fs::path& other() { return other_; }

  struct Server {
    int port = free_port();
    int pid = 0;
    std::string url() const { return "http://127.0.0.1:" + std::to_string(port) + "/"; }
    void start(const fs::path& dir) {
      pid = spawn_relief({"serve", dir.string(), "--port", std::to_string(port)});
      wait_for(port);
    }
    void stop() {
      if (pid == 0) return;
      ::kill(pid, SIGTERM);
      ::waitpid(pid, nullptr, 0);
      pid = 0;
    }
    ~Server() { stop(); }
  };

  static Result<tiles::Store> open_cached(const std::string& url, const fs::path& cache_dir,
                                          std::shared_ptr<net::DiskCache>* cache = nullptr) {
    auto source = RELIEF_TRY(net::source_for(url));
    auto c = RELIEF_TRY(net::DiskCache::create(std::move(source), cache_dir, uint64_t{1} << 30));
    if (cache) *cache = c;
    return tiles::Store::open(std::shared_ptr<const tiles::StoreSource>(c));
  }

  // A tile both stores hold (a coarse one covers both 1-degree cells) with
  // different samples: what a cache mixing the stores would get wrong.
  static geo::TileKey shared_tile() {
    auto a = tiles::Store::open(store()), b = tiles::Store::open(other());
    for (int l = a->manifest().min_level; l <= a->manifest().max_level; ++l) {
      for (const auto& e : a->index(l).entries()) {
        if (b->has_tile(e.key) && samples(*a, e.key) != samples(*b, e.key)) return e.key;
      }
    }
    ADD_FAILURE() << "the two stores share no tile";
    return {};
  }
  static std::vector<std::byte> samples(const tiles::Store& s, const geo::TileKey& key) {
    auto t = s.read_tile(key);
    EXPECT_TRUE(t) << t.error().message;
    if (!t) return {};
    return {t->raster.bytes().begin(), t->raster.bytes().end()};
  }
  static void expect_reads_like(const tiles::Store& remote, const fs::path& local_dir,
                                const geo::TileKey& key) {
    auto local = tiles::Store::open(local_dir);
    EXPECT_EQ(remote.manifest().to_json(), local->manifest().to_json());
    EXPECT_TRUE(samples(remote, key) == samples(*local, key)) << key.to_string();
  }

 private:
  static inline fs::path other_;
};

TEST_F(CacheIdentityTest, TwoStoresThroughOneCacheDirectoryReadTheirOwnData) {
  const geo::TileKey key = shared_tile();
  Server a, b;
  a.start(store());
  b.start(other());
  ScratchDir cache_dir("cache_two_stores");
  for (int round = 0; round < 2; ++round) {  // the second round from the cache
    auto from_a = open_cached(a.url(), cache_dir.path());
    ASSERT_TRUE(from_a) << from_a.error().message;
    expect_reads_like(*from_a, store(), key);
    auto from_b = open_cached(b.url(), cache_dir.path());
    ASSERT_TRUE(from_b) << from_b.error().message;
    expect_reads_like(*from_b, other(), key);
  }
}

TEST_F(CacheIdentityTest, AStoreChangedAtTheSameUrlIsNotServedStaleAndReadsOffline) {
  const geo::TileKey key = shared_tile();
  ScratchDir served("cache_changed_store"), cache_dir("cache_changed_cache");
  const fs::path dir = served / "store";
  fs::copy(store(), dir, fs::copy_options::recursive);
  Server server;
  server.start(dir);
  {
    auto first = open_cached(server.url(), cache_dir.path());
    ASSERT_TRUE(first) << first.error().message;
    expect_reads_like(*first, store(), key);
  }
  // The store is rebuilt from other data and served again at the same URL.
  server.stop();
  fs::remove_all(dir);
  fs::copy(other(), dir, fs::copy_options::recursive);
  server.start(dir);
  {
    auto changed = open_cached(server.url(), cache_dir.path());
    ASSERT_TRUE(changed) << changed.error().message;
    expect_reads_like(*changed, other(), key);
  }
  // The server gone, the store last seen there reads from the cache.
  server.stop();
  std::shared_ptr<net::DiskCache> cache;
  auto offline = open_cached(server.url(), cache_dir.path(), &cache);
  ASSERT_TRUE(offline) << offline.error().message;
  expect_reads_like(*offline, other(), key);
  EXPECT_EQ(cache->stats().misses, 0u);
}

}  // namespace
}  // namespace relief::testing
