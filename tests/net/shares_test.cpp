// A store spread cyclically over servers (seed 000 §3.1): `relief split`
// shares behind three nginx servers and `relief serve --share i/3` over the
// whole store both read as the one store, tile for tile, and render the same
// frame; each server holds (or answers for) only its own tiles.
#include <gtest/gtest.h>

#include <signal.h>
#include <sys/wait.h>

#include <fmt/format.h>

#include "relief/base/file_io.h"
#include "relief/net/http_source.h"
#include "relief/serve/store_server.h"
#include "relief/tiles/split.h"
#include "relief/tiles/store.h"
#include "relief/tiles/store_layout.h"
#include "servers.h"
#include "test_support.h"

namespace relief::testing {
namespace {
namespace fs = std::filesystem;

constexpr uint32_t kShares = 3;

class SharesTest : public SmallStoreSuite {
 protected:
  // Every tile of the local store, read through `location`, is the same file.
  static void expect_same_store(const std::string& location) {
    auto source = net::source_for(location);
    ASSERT_TRUE(source) << source.error().message;
    auto local = tiles::local_source(store().string());
    const tiles::Store s = *tiles::Store::open(store());
    size_t tiles = 0;
    for (int level = s.manifest().min_level; level <= s.manifest().max_level; ++level) {
      for (const tiles::IndexEntry& e : s.index(level).entries()) {
        const std::string path = tiles::tile_relative_path(e.key);
        auto remote_bytes = (*source)->fetch(path);
        ASSERT_TRUE(remote_bytes) << remote_bytes.error().message;
        EXPECT_EQ(*remote_bytes, *local->fetch(path)) << path;
        ++tiles;
      }
    }
    EXPECT_GT(tiles, 20u);
    // Each tile asked of its own server only: mirrors would fail over.
    auto http = std::dynamic_pointer_cast<const net::HttpSource>(*source);
    ASSERT_TRUE(http);
    EXPECT_EQ(http->stats().failovers, 0u);
    EXPECT_EQ(http->stats().requests, tiles);
  }

  static std::string cyclic_url(const std::vector<int>& ports) {
    std::string url = "cyclic:";
    for (size_t i = 0; i < ports.size(); ++i) {
      url += fmt::format("{}http://127.0.0.1:{}/", i ? "," : "", ports[i]);
    }
    return url;
  }

  static std::vector<uint8_t> render(const std::string& location, const std::string& name) {
    const fs::path png = scratch().path() / (name + ".png");
    const RunResult r = run_relief({"render", location, "--look-at", "1.5,42.5,1500,40000,0,-30",
                                    "--size", "160x120", "-o", png.string()},
                                   kNoMesaLeakReport);
    EXPECT_EQ(r.exit_code, 0) << r.err;
    auto bytes = read_file(png, kNoSizeLimit);
    EXPECT_TRUE(bytes) << png;
    if (!bytes) return {};
    return {reinterpret_cast<const uint8_t*>(bytes->data()),
            reinterpret_cast<const uint8_t*>(bytes->data()) + bytes->size()};
  }
};

TEST_F(SharesTest, SplitSharesBehindNginxAreDisjointAndReadAsTheStore) {
  const fs::path out = scratch().path() / "split";
  auto report = tiles::split_store(store(), out, kShares);
  ASSERT_TRUE(report) << report.error().message;
  const tiles::Store s = *tiles::Store::open(store());
  uint64_t tiles = 0;
  for (int level = s.manifest().min_level; level <= s.manifest().max_level; ++level) {
    for (const tiles::IndexEntry& e : s.index(level).entries()) {
      const std::string path = tiles::tile_relative_path(e.key);
      for (uint32_t i = 0; i < kShares; ++i) {
        EXPECT_EQ(fs::exists(tiles::share_directory(out, i) / path), e.key.morton() % kShares == i)
            << path << " in share " << i;
      }
      ++tiles;
    }
  }
  EXPECT_EQ(report->tiles, tiles);
  std::vector<int> ports, pids;
  for (uint32_t i = 0; i < kShares; ++i) {
    ports.push_back(free_port());
    pids.push_back(start_nginx(tiles::share_directory(out, i),
                               scratch().path() / fmt::format("nginx-{}", i), ports.back()));
  }
  expect_same_store(cyclic_url(ports));
  EXPECT_EQ(render(cyclic_url(ports), "nginx-shares"), render(store().string(), "local"));
  // As mirrors instead, a share misses two thirds of the tiles.
  auto one = net::source_for(fmt::format("http://127.0.0.1:{}/", ports[0]));
  size_t missing = 0;
  for (const tiles::IndexEntry& e : s.index(s.manifest().max_level).entries()) {
    missing += !(*one)->fetch(tiles::tile_relative_path(e.key));
  }
  EXPECT_GT(missing, 0u);
  for (int pid : pids) {
    ::kill(pid, SIGTERM);
    ::waitpid(pid, nullptr, 0);
  }
}

TEST_F(SharesTest, ServedSharesAnswerOnlyForTheirTiles) {
  std::vector<std::unique_ptr<serve::StoreServer>> servers;
  std::vector<int> ports;
  for (uint32_t i = 0; i < kShares; ++i) {
    serve::ServeOptions o;
    o.root = store();
    o.port = 0;
    o.threads = 2;
    o.share_index = i;
    o.share_count = kShares;
    auto server = serve::StoreServer::start(o);
    ASSERT_TRUE(server) << server.error().message;
    ports.push_back((*server)->port());
    servers.push_back(std::move(*server));
  }
  expect_same_store(cyclic_url(ports));
  // Each server: the manifest and indices, and only its own tiles.
  for (uint32_t i = 0; i < kShares; ++i) {
    net::HttpOptions o;
    o.base_urls = {fmt::format("http://127.0.0.1:{}/", ports[i])};
    o.attempts = 1;
    auto source = *net::HttpSource::create(o);
    EXPECT_TRUE(source->fetch(tiles::kManifestName));
    const geo::TileKey mine = geo::TileKey::from_morton(10, 3 * 1000 + i);
    const geo::TileKey other = geo::TileKey::from_morton(10, 3 * 1000 + (i + 1) % kShares);
    EXPECT_TRUE(serve::in_share(tiles::tile_relative_path(mine), i, kShares));
    EXPECT_FALSE(serve::in_share(tiles::tile_relative_path(other), i, kShares));
  }
  const tiles::Store s = *tiles::Store::open(store());
  const tiles::IndexEntry& e = s.index(s.manifest().max_level).entries().front();
  const uint32_t owner = static_cast<uint32_t>(e.key.morton() % kShares);
  net::HttpOptions o;
  o.base_urls = {fmt::format("http://127.0.0.1:{}/", ports[(owner + 1) % kShares])};
  o.attempts = 1;
  auto wrong = (*net::HttpSource::create(o))->fetch(tiles::tile_relative_path(e.key));
  ASSERT_FALSE(wrong);
  EXPECT_NE(wrong.error().message.find("404"), std::string::npos) << wrong.error().message;
}

TEST_F(SharesTest, BadSharesAreOneLineErrors) {
  EXPECT_TRUE(is_one_line_error(run_relief({"serve", store().string(), "--share", "3/3"}),
                                "--share: '3/3'"));
  EXPECT_TRUE(
      is_one_line_error(run_relief({"serve", store().string(), "--share", "x"}), "--share: 'x'"));
  const fs::path out = scratch().path() / "bad-split";
  EXPECT_TRUE(is_one_line_error(
      run_relief({"split", store().string(), "-o", out.string(), "--shares", "1"}), "--shares"));
  fs::create_directories(out);
  EXPECT_TRUE(is_one_line_error(
      run_relief({"split", store().string(), "-o", out.string(), "--shares", "2"}),
      "already exists"));
  EXPECT_TRUE(fs::is_empty(out));
  EXPECT_TRUE(is_one_line_error(run_relief({"split", (scratch().path() / "nope").string(), "-o",
                                            (scratch().path() / "x").string(), "--shares", "2"}),
                                "nope"));
  EXPECT_FALSE(fs::exists(scratch().path() / "x"));
}

}  // namespace
}  // namespace relief::testing
