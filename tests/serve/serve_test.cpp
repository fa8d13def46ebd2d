// `relief serve` on loopback: store files byte for byte with the right
// headers, keep-alive, ETag revalidation, many clients at once; every request
// outside the store refused; and a real nginx serving the same directory
// answers identically.
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

#include "relief/base/file_io.h"
#include "relief/serve/store_server.h"
#include "servers.h"
#include "test_support.h"

namespace relief::testing {
namespace {
namespace fs = std::filesystem;

struct Response {
  int status = 0;
  std::map<std::string, std::string> headers;  // lower-case names
  std::string body;
};

// Reads one response from a connection (Content-Length framed, or to EOF).
Response read_response(int fd, bool head_request = false) {
  std::string data;
  char buf[65536];
  size_t header_end;
  while ((header_end = data.find("\r\n\r\n")) == std::string::npos) {
    const ssize_t n = ::recv(fd, buf, sizeof buf, 0);
    if (n <= 0) return {};
    data.append(buf, static_cast<size_t>(n));
  }
  Response r;
  std::istringstream head(data.substr(0, header_end));
  std::string line;
  std::getline(head, line);
  r.status = std::stoi(line.substr(9, 3));
  while (std::getline(head, line)) {
    if (!line.empty() && line.back() == '\r') line.pop_back();
    const size_t colon = line.find(':');
    if (colon == std::string::npos) continue;
    std::string name = line.substr(0, colon);
    for (char& c : name) c = static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
    r.headers[name] = line.substr(colon + 2);
  }
  r.body = data.substr(header_end + 4);
  const bool framed = r.headers.count("content-length");
  const size_t want = framed ? std::stoul(r.headers["content-length"]) : 0;
  if (head_request || r.status == 304) return r;
  while (framed ? r.body.size() < want : true) {
    const ssize_t n = ::recv(fd, buf, sizeof buf, 0);
    if (n <= 0) break;
    r.body.append(buf, static_cast<size_t>(n));
  }
  return r;
}

Response request(int port, const std::string& raw, bool head = false) {
  const int fd = connect_to(port);
  EXPECT_GE(fd, 0);
  ::send(fd, raw.data(), raw.size(), MSG_NOSIGNAL);
  Response r = read_response(fd, head);
  ::close(fd);
  return r;
}

Response get(int port, const std::string& path) {
  return request(port, "GET " + path + " HTTP/1.1\r\nHost: x\r\nConnection: close\r\n\r\n");
}

std::string file_text(const fs::path& p) {
  auto bytes = read_file(p);
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
  const int fd = connect_to(port_);
  for (int i = 0; i < 5; ++i) {
    const std::string req = "GET /manifest.json HTTP/1.1\r\nHost: x\r\n\r\n";
    ::send(fd, req.data(), req.size(), MSG_NOSIGNAL);
    const Response r = read_response(fd);
    ASSERT_EQ(r.status, 200) << i;
    EXPECT_EQ(r.body, file_text(store_ / "manifest.json"));
  }
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
