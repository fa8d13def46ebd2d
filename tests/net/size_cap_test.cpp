// A hostile server on loopback answers with bodies far larger than any store
// file can be (a 20 GiB Content-Length, an endless chunked body): the HTTP
// source aborts the transfer as soon as the cap the manifest allows is
// exceeded, reports it, and holds no more than the cap in memory.
#include <gtest/gtest.h>

#include <arpa/inet.h>
#include <netinet/in.h>
#include <sys/socket.h>
#include <unistd.h>

#include <atomic>
#include <map>
#include <mutex>
#include <thread>

#include "relief/base/file_io.h"
#include "relief/base/memory_use.h"
#include "relief/base/units.h"
#include "relief/net/http_source.h"
#include "relief/tiles/store.h"
#include "relief/tiles/store_layout.h"
#include "servers.h"
#include "test_support.h"

namespace relief::testing {
namespace {
namespace fs = std::filesystem;

constexpr uint64_t kMiB = uint64_t{1} << 20;
// A hostile answer stops here, so that a client without a cap finishes too.
constexpr uint64_t kHostileLimit = 96 * kMiB;

enum class Answer { File, HugeLength, EndlessChunks };

// Serves a store directory, one request per connection, except for the
// hostile paths; counts the bytes of each path that the client accepted.
class HostileServer {
 public:
  HostileServer(fs::path root, std::map<std::string, Answer> hostile)
      : root_(std::move(root)), hostile_(std::move(hostile)) {
    fd_ = ::socket(AF_INET, SOCK_STREAM, 0);
    sockaddr_in a{};
    a.sin_family = AF_INET;
    a.sin_addr.s_addr = htonl(INADDR_LOOPBACK);
    ::bind(fd_, reinterpret_cast<sockaddr*>(&a), sizeof a);
    ::listen(fd_, 16);
    socklen_t len = sizeof a;
    ::getsockname(fd_, reinterpret_cast<sockaddr*>(&a), &len);
    port_ = ntohs(a.sin_port);
    thread_ = std::thread([this] { run(); });
  }
  ~HostileServer() {
    ::shutdown(fd_, SHUT_RDWR);
    ::close(fd_);
    thread_.join();
  }
  std::string url() const { return "http://127.0.0.1:" + std::to_string(port_) + "/"; }
  uint64_t largest_sent(const std::string& path) {
    std::lock_guard lock(mutex_);
    return sent_[path];
  }

 private:
  void run() {
    for (;;) {
      const int c = ::accept(fd_, nullptr, nullptr);
      if (c < 0) return;
      const std::string path = read_request_path(c);
      const auto it = hostile_.find(path);
      const uint64_t sent = it == hostile_.end() ? serve_file(c, path) : flood(c, it->second);
      {
        std::lock_guard lock(mutex_);
        sent_[path] = std::max(sent_[path], sent);
      }
      ::close(c);
    }
  }
  static bool send_all(int c, const std::string& s) {
    return ::send(c, s.data(), s.size(), MSG_NOSIGNAL) == static_cast<ssize_t>(s.size());
  }
  uint64_t serve_file(int c, const std::string& path) {
    auto bytes = read_file(root_ / path, kNoSizeLimit);
    if (!bytes) {
      send_all(c, "HTTP/1.1 404 Not Found\r\nContent-Length: 0\r\nConnection: close\r\n\r\n");
      return 0;
    }
    send_all(c, "HTTP/1.1 200 OK\r\nContent-Length: " + std::to_string(bytes->size()) +
                    "\r\nConnection: close\r\n\r\n" +
                    std::string(reinterpret_cast<const char*>(bytes->data()), bytes->size()));
    return bytes->size();
  }
  // Headers, then bytes until the client hangs up (or kHostileLimit).
  static uint64_t flood(int c, Answer answer) {
    const bool chunked = answer == Answer::EndlessChunks;
    if (!send_all(c, chunked ? "HTTP/1.1 200 OK\r\nTransfer-Encoding: chunked\r\n\r\n"
                             : "HTTP/1.1 200 OK\r\nContent-Length: 21474836480\r\n\r\n")) {
      return 0;
    }
    const std::string block(64 * 1024, 'x');
    const std::string piece = chunked ? "10000\r\n" + block + "\r\n" : block;
    uint64_t sent = 0;
    while (sent < kHostileLimit && send_all(c, piece)) sent += block.size();
    return sent;
  }

  fs::path root_;
  std::map<std::string, Answer> hostile_;
  int fd_ = -1, port_ = 0;
  std::thread thread_;
  std::mutex mutex_;
  std::map<std::string, uint64_t> sent_;
};

class SizeCapTest : public SmallStoreSuite {
 protected:
  static geo::TileKey a_tile() {
    auto s = tiles::Store::open(store());
    return s->index(s->manifest().max_level).entries().front().key;
  }
  static Result<std::shared_ptr<net::HttpSource>> source(const std::string& url) {
    net::HttpOptions o;
    o.base_urls = {url};
    o.backoff_ms = 1;
    return net::HttpSource::create(o);
  }
};

// What a tile of the small store may be at most: far below what the server sends.
TEST_F(SizeCapTest, TheTileCapComesFromTheManifest) {
  auto s = tiles::Store::open(store());
  const uint64_t cap = tiles::max_file_bytes("0/000.rtile", s->tile_shape());
  EXPECT_LT(cap, 4 * kMiB);
  EXPECT_GE(cap, 2 * s->tile_shape().raster_bytes());
  // Indices: as large as a full level, at most kMaxLevelIndexBytes.
  EXPECT_LT(tiles::max_file_bytes("0/index.rli", std::nullopt), 100u);
  EXPECT_EQ(tiles::max_file_bytes("20/index.rli", std::nullopt), tiles::kMaxLevelIndexBytes);
  EXPECT_EQ(tiles::max_file_bytes("manifest.json", std::nullopt), tiles::kMaxManifestBytes);
}

TEST_F(SizeCapTest, HugeOrEndlessTileBodiesAreCutAtTheCap) {
  for (Answer answer : {Answer::HugeLength, Answer::EndlessChunks}) {
    const geo::TileKey key = a_tile();
    const std::string tile = tiles::tile_relative_path(key);
    HostileServer server(store(), {{tile, answer}});
    auto http = source(server.url());
    ASSERT_TRUE(http);
    auto remote = tiles::Store::open(std::shared_ptr<const tiles::StoreSource>(*http));
    ASSERT_TRUE(remote) << remote.error().message;
    const uint64_t rss_before = resident_set_bytes();
    auto t = remote->read_tile(key);
    ASSERT_FALSE(t);
    const uint64_t cap = tiles::max_file_bytes(tile, remote->tile_shape());
    EXPECT_EQ(t.error().message, server.url() + tile + ": response larger than " +
                                     format_bytes(cap) + ", the most this file can be");
    // Aborted at the cap: not retried, and the server could not send much more
    // than the cap plus what the sockets buffer.
    EXPECT_EQ((*http)->stats().retries, 0u);
    EXPECT_LT(server.largest_sent(tile), cap + 32 * kMiB);
    EXPECT_LT(resident_set_bytes(), rss_before + 32 * kMiB);
    // The rest of the store still reads.
    auto others = remote->index(key.level).entries();
    ASSERT_GT(others.size(), 1u);
    EXPECT_TRUE(remote->read_tile(others.back().key));
  }
}

TEST_F(SizeCapTest, AHugeManifestIsRefusedBeforeItsBody) {
  HostileServer server(store(), {{tiles::kManifestName, Answer::HugeLength}});
  auto http = source(server.url());
  ASSERT_TRUE(http);
  auto remote = tiles::Store::open(std::shared_ptr<const tiles::StoreSource>(*http));
  ASSERT_FALSE(remote);
  EXPECT_EQ(remote.error().message, server.url() + "manifest.json: response larger than " +
                                        format_bytes(tiles::kMaxManifestBytes) +
                                        ", the most this file can be");
  EXPECT_LT(server.largest_sent(tiles::kManifestName), 32 * kMiB);
  // Through the command line: a one-line error, non-zero exit.
  auto info = run_relief({"info", server.url()});
  EXPECT_TRUE(is_one_line_error(info, "response larger than")) << info.err;
}

}  // namespace
}  // namespace relief::testing
