// Stores over HTTP through libcurl: against `relief serve` and nginx on
// loopback the remote store reads exactly like the local one; a fake server
// injects what real servers rarely do on demand (500s, truncated bodies,
// corrupt bytes, a dead mirror) and the source retries, fails over, reports,
// and never returns bad data.
#include <gtest/gtest.h>

#include <arpa/inet.h>
#include <netinet/in.h>
#include <signal.h>
#include <sys/socket.h>
#include <sys/wait.h>
#include <unistd.h>

#include <atomic>
#include <chrono>
#include <functional>
#include <thread>

#include "relief/base/file_io.h"
#include "relief/net/http_source.h"
#include "relief/tiles/store.h"
#include "relief/tiles/store_layout.h"
#include "servers.h"
#include "test_support.h"

namespace relief::testing {
namespace {
namespace fs = std::filesystem;

int listen_any(int& port) {
  const int fd = ::socket(AF_INET, SOCK_STREAM, 0);
  const int one = 1;
  ::setsockopt(fd, SOL_SOCKET, SO_REUSEADDR, &one, sizeof one);
  sockaddr_in a{};
  a.sin_family = AF_INET;
  a.sin_addr.s_addr = htonl(INADDR_LOOPBACK);
  ::bind(fd, reinterpret_cast<sockaddr*>(&a), sizeof a);
  ::listen(fd, 64);
  socklen_t len = sizeof a;
  ::getsockname(fd, reinterpret_cast<sockaddr*>(&a), &len);
  port = ntohs(a.sin_port);
  return fd;
}

// A one-request-per-connection HTTP server whose answers a test scripts:
// respond(path, n) gives the raw bytes for the n-th request of that path.
class FakeServer {
 public:
  using Respond = std::function<std::string(const std::string& path, int n)>;
  explicit FakeServer(Respond respond) : respond_(std::move(respond)) {
    fd_ = listen_any(port_);
    thread_ = std::thread([this] { run(); });
  }
  ~FakeServer() {
    stop_ = true;
    ::shutdown(fd_, SHUT_RDWR);
    ::close(fd_);
    thread_.join();
  }
  std::string url() const { return "http://127.0.0.1:" + std::to_string(port_) + "/"; }

 private:
  void run() {
    std::map<std::string, int> counts;
    while (!stop_) {
      const int c = ::accept(fd_, nullptr, nullptr);
      if (c < 0) return;
      const std::string path = read_request_path(c);
      const std::string out = respond_(path, counts[path]++);
      ::send(c, out.data(), out.size(), MSG_NOSIGNAL);
      ::close(c);
    }
  }
  Respond respond_;
  int fd_ = -1, port_ = 0;
  std::atomic<bool> stop_{false};
  std::thread thread_;
};

std::string ok(const std::string& body) {
  return "HTTP/1.1 200 OK\r\nContent-Length: " + std::to_string(body.size()) +
         "\r\nConnection: close\r\n\r\n" + body;
}
const std::string kError =
    "HTTP/1.1 500 Internal Server Error\r\nContent-Length: 0\r\nConnection: close\r\n\r\n";
const std::string kMissing =
    "HTTP/1.1 404 Not Found\r\nContent-Length: 0\r\nConnection: close\r\n\r\n";

class HttpSourceTest : public SmallStoreSuite {
 protected:
  static std::string file(const std::string& relative) {
    auto b = read_file(store() / relative, kNoSizeLimit);
    return std::string(reinterpret_cast<const char*>(b->data()), b->size());
  }
  static std::string a_tile() {
    auto s = tiles::Store::open(store());
    return tiles::tile_relative_path(s->index(s->manifest().max_level).entries().front().key);
  }
  static net::HttpOptions fast(std::vector<std::string> urls) {
    net::HttpOptions o;
    o.base_urls = std::move(urls);
    o.backoff_ms = 1;
    o.timeout_ms = 3000;
    return o;
  }
};

// Every tile of the remote store decodes to the local one's samples.
void expect_same_store(const tiles::Store& local, const tiles::Store& remote) {
  EXPECT_EQ(remote.manifest().to_json(), local.manifest().to_json());
  for (int l = local.manifest().min_level; l <= local.manifest().max_level; ++l) {
    ASSERT_EQ(remote.index(l).size(), local.index(l).size());
    for (const auto& e : local.index(l).entries()) {
      auto a = local.read_tile(e.key), b = remote.read_tile(e.key);
      ASSERT_TRUE(a && b) << (b ? "" : b.error().message);
      ASSERT_EQ(a->raster.bytes().size(), b->raster.bytes().size());
      ASSERT_TRUE(std::equal(a->raster.bytes().begin(), a->raster.bytes().end(),
                             b->raster.bytes().begin()));
    }
  }
}

TEST_F(HttpSourceTest, RemoteStoresReadLikeLocalOnes) {
  int port = 0;
  ::close(listen_any(port));
  const int pid = spawn_relief({"serve", store().string(), "--port", std::to_string(port)});
  const std::string url = "http://127.0.0.1:" + std::to_string(port) + "/";
  auto source = net::HttpSource::create(fast({url}));
  ASSERT_TRUE(source);
  std::shared_ptr<const tiles::StoreSource> s = *source;
  Result<tiles::Store> remote = fail("not yet");
  // Until the server listens (a bound in real time only as a safety net).
  for (int i = 0; i < 3000 && !remote; ++i) {
    remote = tiles::Store::open(s);
    if (!remote) std::this_thread::sleep_for(std::chrono::milliseconds(20));
  }
  ASSERT_TRUE(remote) << remote.error().message;
  expect_same_store(*tiles::Store::open(store()), *remote);
  // Through the command line, too.
  auto info = run_relief({"info", url});
  EXPECT_EQ(info.exit_code, 0) << info.err;
  EXPECT_NE(info.out.find("elevation"), std::string::npos);
  ::kill(pid, SIGTERM);
  ::waitpid(pid, nullptr, 0);
}

TEST_F(HttpSourceTest, RetriesErrorsTruncationAndCorruption) {
  const std::string tile = a_tile(), good = file(tile);
  std::string corrupt = good;
  corrupt[corrupt.size() - 1] ^= 0x5a;  // in the payload: the CRC catches it
  FakeServer flaky([&](const std::string& path, int n) {
    if (path != tile) return kMissing;
    switch (n) {
      case 0:
        return kError;
      case 1:
        return ok(corrupt);
      case 2:  // a body cut short
        return "HTTP/1.1 200 OK\r\nContent-Length: " + std::to_string(good.size()) + "\r\n\r\n" +
               good.substr(0, good.size() / 2);
      default:
        return ok(good);
    }
  });
  auto source = net::HttpSource::create(fast({flaky.url()}));
  ASSERT_TRUE(source);
  auto bytes = (*source)->fetch(tile);
  ASSERT_TRUE(bytes) << bytes.error().message;
  EXPECT_EQ(std::string(reinterpret_cast<const char*>(bytes->data()), bytes->size()), good);
  const net::HttpStats st = (*source)->stats();
  EXPECT_EQ(st.retries, 3u);
  EXPECT_EQ(st.rejected, 1u);
  // A 404 is an answer, not a fault: no retries.
  auto missing = (*source)->fetch("10/fff.rtile");
  ASSERT_FALSE(missing);
  EXPECT_NE(missing.error().message.find("404"), std::string::npos);
  EXPECT_EQ((*source)->stats().retries, 3u);
}

TEST_F(HttpSourceTest, AlwaysCorruptDataIsNeverReturned) {
  const std::string tile = a_tile();
  std::string corrupt = file(tile);
  corrupt[corrupt.size() / 2] ^= 1;
  FakeServer bad([&](const std::string&, int) { return ok(corrupt); });
  auto source = net::HttpSource::create(fast({bad.url()}));
  auto bytes = (*source)->fetch(tile);
  ASSERT_FALSE(bytes);
  EXPECT_NE(bytes.error().message.find("checksum"), std::string::npos) << bytes.error().message;
  EXPECT_EQ((*source)->stats().rejected, 4u);
}

TEST_F(HttpSourceTest, MirrorsFailOverAndDistributedTilesStayOnTheirServer) {
  int dead_port = 0;
  ::close(listen_any(dead_port));  // nothing listens there any more
  const std::string dead = "http://127.0.0.1:" + std::to_string(dead_port) + "/";
  FakeServer alive([&](const std::string& path, int) {
    std::error_code ec;
    return fs::is_regular_file(store() / path, ec) ? ok(file(path)) : kMissing;
  });
  auto mirrors = net::HttpSource::create(fast({dead, alive.url()}));
  std::shared_ptr<const tiles::StoreSource> m = *mirrors;
  auto remote = tiles::Store::open(m);
  ASSERT_TRUE(remote) << remote.error().message;
  expect_same_store(*tiles::Store::open(store()), *remote);
  EXPECT_GT((*mirrors)->stats().failovers, 0u);
  // Distributed: tile i lives on server i mod 2; with server 0 dead, exactly
  // the tiles of server 1 can be read.
  auto dist_options = fast({dead, alive.url()});
  dist_options.layout = net::ServerLayout::Distributed;
  dist_options.attempts = 1;
  auto dist = net::HttpSource::create(dist_options);
  auto local = tiles::Store::open(store());
  int readable = 0, unreadable = 0;
  for (const auto& e : local->index(local->manifest().max_level).entries()) {
    const bool ok_read = (*dist)->fetch(tiles::tile_relative_path(e.key)).has_value();
    EXPECT_EQ(ok_read, e.key.morton() % 2 == 1) << e.key.to_string();
    (ok_read ? readable : unreadable)++;
  }
  EXPECT_GT(readable, 0);
  EXPECT_GT(unreadable, 0);
}

TEST(HttpSourceOptions, BadLocationsAreErrors) {
  EXPECT_FALSE(net::HttpSource::create({}));
  net::HttpOptions o;
  o.base_urls = {"ftp://example/"};
  EXPECT_FALSE(net::HttpSource::create(o));
}

}  // namespace
}  // namespace relief::testing
