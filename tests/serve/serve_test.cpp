// `relief serve` on loopback: store files byte for byte with the right
// headers, keep-alive, ETag revalidation, byte ranges, many clients at once;
// every request outside the store refused; and a real nginx serving the same
// directory answers identically.
#include <gtest/gtest.h>

#include <arpa/inet.h>
#include <netinet/in.h>
#include <signal.h>
#include <sys/socket.h>
#include <sys/wait.h>
#include <unistd.h>

#include <atomic>
#include <chrono>
#include <fstream>
#include <map>
#include <sstream>
#include <thread>

#include <fmt/format.h>

#include "http_client.h"
#include "relief/base/file_io.h"
#include "relief/serve/store_server.h"
#include "servers.h"
#include "test_support.h"

namespace relief::testing {
namespace {
namespace fs = std::filesystem;

std::string file_text(const fs::path& p) {
  auto bytes = read_file(p, kNoSizeLimit);
  return std::string(reinterpret_cast<const char*>(bytes->data()), bytes->size());
}

class ServeTest : public SmallStoreSuite {
 protected:
  static void SetUpTestSuite() {
    SmallStoreSuite::SetUpTestSuite();
    store_ = store();
    std::ofstream(store_ / "secret.txt") << "not a store file";
    port_ = free_port();
    pid_ = spawn_relief({"serve", store_.string(), "--port", std::to_string(port_)});
    wait_for(port_);
  }
  static void TearDownTestSuite() {
    ::kill(pid_, SIGTERM);
    int status = 0;
    ::waitpid(pid_, &status, 0);
    EXPECT_TRUE(WIFEXITED(status) && WEXITSTATUS(status) == 0)
        << "relief serve did not stop cleanly";
    SmallStoreSuite::TearDownTestSuite();
  }
  static std::string some_tile() {
    for (const auto& e : fs::recursive_directory_iterator(store_)) {
      // Not `"/" + string&&`: gcc 12 -O3 reports a false -Wrestrict there.
      if (e.path().extension() == ".rtile")
        return (fs::path("/") / fs::relative(e.path(), store_)).string();
    }
    return {};
  }
  static inline fs::path store_;
  static inline int port_ = 0, pid_ = 0;
};

TEST_F(ServeTest, StoreFilesWithHeaders) {
  for (const std::string& path :
       {std::string("/manifest.json"), std::string("/10/index.rli"), some_tile()}) {
    SCOPED_TRACE(path);
    const Response r = get(port_, path);
    ASSERT_EQ(r.status, 200);
    EXPECT_EQ(r.body, file_text(store_ / path.substr(1)));
    EXPECT_EQ(r.headers.at("content-length"), std::to_string(r.body.size()));
    EXPECT_FALSE(r.headers.at("etag").empty());
    EXPECT_NE(r.headers.at("cache-control").find("max-age"), std::string::npos);
    // HEAD: the same headers, no body.
    const Response h =
        request(port_, "HEAD " + path + " HTTP/1.1\r\nHost: x\r\nConnection: close\r\n\r\n", true);
    EXPECT_EQ(h.status, 200);
    EXPECT_EQ(h.headers.at("content-length"), r.headers.at("content-length"));
    EXPECT_TRUE(h.body.empty());
    // Revalidation.
    const Response n = request(port_, "GET " + path + " HTTP/1.1\r\nHost: x\r\nIf-None-Match: " +
                                          r.headers.at("etag") + "\r\nConnection: close\r\n\r\n");
    EXPECT_EQ(n.status, 304);
    EXPECT_TRUE(n.body.empty());
  }
}

TEST_F(ServeTest, KeepAliveServesSeveralRequestsOnOneConnection) {
  const int fd = connect_client(port_);
  for (int i = 0; i < 5; ++i) {
    const std::string req = "GET /manifest.json HTTP/1.1\r\nHost: x\r\n\r\n";
    ::send(fd, req.data(), req.size(), MSG_NOSIGNAL);
    const Response r = read_response(fd);
    ASSERT_EQ(r.status, 200) << i;
    EXPECT_EQ(r.body, file_text(store_ / "manifest.json"));
  }
  ::close(fd);
}

// Answers to HEAD carry no body, errors included, so the next answer on the
// connection is read from its start.
TEST_F(ServeTest, HeadAnswersHaveNoBodyOnAKeptConnection) {
  const int fd = connect_client(port_);
  const std::string head = "HEAD /10/fff.rtile HTTP/1.1\r\nHost: x\r\n\r\n";
  ::send(fd, head.data(), head.size(), MSG_NOSIGNAL);
  const Response h = read_response(fd, true);
  EXPECT_EQ(h.status, 404);
  EXPECT_EQ(h.body, "");  // nothing after the head
  const std::string get = "GET /manifest.json HTTP/1.1\r\nHost: x\r\n\r\n";
  ::send(fd, get.data(), get.size(), MSG_NOSIGNAL);
  const Response r = read_response(fd);
  EXPECT_EQ(r.status, 200);
  EXPECT_EQ(r.body, file_text(store_ / "manifest.json"));
  ::close(fd);
}

TEST_F(ServeTest, RequestsOutsideTheStoreAreRefused) {
  for (const char* path :
       {"/../../etc/passwd", "/secret.txt", "/10/../manifest.json", "//manifest.json",
        "/%2e%2e/%2e%2e/etc/passwd", "/./manifest.json", "/10/index.rli/", "/.build/state.json",
        "/manifest.json?x=1", "/", "/10", "/10/"}) {
    SCOPED_TRACE(path);
    const Response r = get(port_, path);
    EXPECT_EQ(r.status, 404);
    EXPECT_EQ(r.body.find("not a store file"), std::string::npos);
    EXPECT_EQ(r.body.find("root:"), std::string::npos);
  }
  EXPECT_EQ(
      request(port_, "POST /manifest.json HTTP/1.1\r\nHost: x\r\nContent-Length: 0\r\n\r\n").status,
      405);
  EXPECT_EQ(request(port_, "GARBAGE\r\n\r\n").status, 400);
  EXPECT_EQ(request(port_, "GET /manifest.json HTTP/9.9\r\n\r\n").status, 400);
  const std::string huge =
      "GET /manifest.json HTTP/1.1\r\nX-Pad: " + std::string(20000, 'a') + "\r\n\r\n";
  EXPECT_EQ(request(port_, huge).status, 431);
  // The server is still fine.
  EXPECT_EQ(get(port_, "/manifest.json").status, 200);
}

// The last header field counts like the others (the head used to be cut
// before its final line break, so a field sent last was dropped).
TEST_F(ServeTest, TheLastHeaderFieldCounts) {
  const std::string tile = some_tile();
  const Response first = get(port_, tile);
  ASSERT_EQ(first.status, 200);
  const std::string etag = first.headers.at("etag");
  // Connection: close, sent last, ends the connection after the answer.
  const int fd = connect_client(port_);
  const std::string close_last =
      "GET " + tile + " HTTP/1.1\r\nHost: x\r\nConnection: close\r\n\r\n";
  ::send(fd, close_last.data(), close_last.size(), MSG_NOSIGNAL);
  EXPECT_EQ(read_response(fd).status, 200);
  EXPECT_TRUE(closed_by_server(fd));
  ::close(fd);
  // If-None-Match sent last revalidates.
  EXPECT_EQ(
      request(port_, "GET " + tile + " HTTP/1.1\r\nHost: x\r\nIf-None-Match: " + etag + "\r\n\r\n")
          .status,
      304);
  // "*" matches any current version of a file that exists; a list matches by any member.
  EXPECT_EQ(request(port_, "GET " + tile + " HTTP/1.1\r\nIf-None-Match: *\r\n\r\n").status, 304);
  EXPECT_EQ(request(port_, "GET " + tile + " HTTP/1.1\r\nIf-None-Match: \"x\", W/" + etag +
                               "\r\nHost: x\r\n\r\n")
                .status,
            304);
  EXPECT_EQ(request(port_, "GET " + tile + " HTTP/1.1\r\nIf-None-Match: \"other\"\r\n\r\n").status,
            200);
  EXPECT_EQ(request(port_, "GET /10/fff.rtile HTTP/1.1\r\nIf-None-Match: *\r\n\r\n").status, 404);
}

// Single byte ranges: 206 with Content-Range, 416 past the end; several
// ranges or a stale If-Range give the whole file.
TEST_F(ServeTest, SingleByteRanges) {
  const std::string tile = some_tile(), whole = file_text(store_ / tile.substr(1));
  ASSERT_GT(whole.size(), 100u);
  const size_t size = whole.size();
  const auto ranged = [&](const std::string& range) {
    return request(port_, "GET " + tile + " HTTP/1.1\r\nHost: x\r\nRange: " + range + "\r\n\r\n");
  };
  Response r = ranged("bytes=10-19");
  EXPECT_EQ(r.status, 206);
  EXPECT_EQ(r.body, whole.substr(10, 10));
  EXPECT_EQ(r.headers["content-range"], fmt::format("bytes 10-19/{}", size));
  r = ranged("bytes=-7");
  EXPECT_EQ(r.status, 206);
  EXPECT_EQ(r.body, whole.substr(size - 7));
  r = ranged("bytes=50-");
  EXPECT_EQ(r.status, 206);
  EXPECT_EQ(r.body, whole.substr(50));
  r = ranged("bytes=0-99999999");
  EXPECT_EQ(r.status, 206);
  EXPECT_EQ(r.body, whole);
  r = ranged(fmt::format("bytes={}-", size));
  EXPECT_EQ(r.status, 416);
  EXPECT_EQ(r.headers["content-range"], fmt::format("bytes */{}", size));
  EXPECT_EQ(ranged("bytes=0-1,5-6").body, whole);
  EXPECT_EQ(ranged("items=0-1").status, 200);
  const std::string etag = get(port_, tile).headers.at("etag");
  r = request(port_,
              "GET " + tile + " HTTP/1.1\r\nRange: bytes=0-3\r\nIf-Range: " + etag + "\r\n\r\n");
  EXPECT_EQ(r.status, 206);
  r = request(port_, "GET " + tile + " HTTP/1.1\r\nRange: bytes=0-3\r\nIf-Range: \"old\"\r\n\r\n");
  EXPECT_EQ(r.status, 200);
  EXPECT_EQ(r.body, whole);
}

TEST_F(ServeTest, ManyClientsAtOnce) {
  const std::string tile = some_tile(), expected = file_text(store_ / tile.substr(1));
  std::atomic<int> good{0};
  std::vector<std::thread> clients;
  for (int c = 0; c < 24; ++c) {
    clients.emplace_back([&] {
      for (int i = 0; i < 10; ++i) {
        const Response r = get(port_, tile);
        if (r.status == 200 && r.body == expected) ++good;
      }
    });
  }
  for (auto& t : clients) t.join();
  EXPECT_EQ(good.load(), 240);
}

TEST_F(ServeTest, NginxServesTheSameStoreIdentically) {
  const int port = free_port();
  const int nginx = start_nginx(store_, scratch().path() / "nginx", port);
  for (const std::string& path : {std::string("/manifest.json"), std::string("/10/index.rli"),
                                  some_tile(), std::string("/10/fff.rtile")}) {
    SCOPED_TRACE(path);
    const Response a = get(port_, path), b = get(port, path);
    EXPECT_EQ(a.status, b.status);
    if (a.status == 200) {
      EXPECT_EQ(a.body, b.body);
      EXPECT_EQ(a.headers.at("content-length"), b.headers.at("content-length"));
    }
  }
  // Ranges and conditional requests on a tile, the header sent last.
  const std::string tile = some_tile();
  for (const std::string& field :
       {std::string("Range: bytes=3-40"), std::string("Range: bytes=-9"),
        std::string("Range: bytes=99999999-"), std::string("If-None-Match: *")}) {
    SCOPED_TRACE(field);
    const std::string raw = "GET " + tile + " HTTP/1.1\r\nHost: x\r\n" + field + "\r\n\r\n";
    Response a = request(port_, raw), b = request(port, raw);
    EXPECT_EQ(a.status, b.status);
    if (a.status == 206) {
      EXPECT_EQ(a.body, b.body);
      EXPECT_EQ(a.headers["content-range"], b.headers["content-range"]);
    }
  }
  ::kill(nginx, SIGTERM);
  ::waitpid(nginx, nullptr, 0);
}

TEST(StorePaths, OnlyCanonicalStorePathsNameFiles) {
  EXPECT_EQ(serve::store_file_for("/manifest.json"), "manifest.json");
  EXPECT_EQ(serve::store_file_for("/3/index.rli"), "3/index.rli");
  EXPECT_FALSE(serve::store_file_for("/3/../manifest.json"));
  EXPECT_FALSE(serve::store_file_for("/03/index.rli"));
  EXPECT_FALSE(serve::store_file_for("manifest.json"));
  EXPECT_FALSE(serve::store_file_for("/state.json"));
}

}  // namespace
}  // namespace relief::testing
