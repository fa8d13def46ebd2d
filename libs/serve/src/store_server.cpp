#include "relief/serve/store_server.h"

#include <arpa/inet.h>
#include <fcntl.h>
#include <netinet/in.h>
#include <netinet/tcp.h>
#include <sys/sendfile.h>
#include <sys/socket.h>
#include <sys/stat.h>
#include <unistd.h>

#include <atomic>
#include <condition_variable>
#include <cstring>
#include <deque>
#include <mutex>
#include <thread>
#include <vector>

#include <fmt/format.h>

#include "relief/tiles/store_layout.h"

namespace relief::serve {
namespace {

constexpr size_t kMaxHeaderBytes = 8192;
constexpr int kIdleSeconds = 10;

struct Request {
  std::string method, path, version;
  bool keep_alive = true;
  std::string if_none_match;
};

bool send_all(int fd, const std::string& s) {
  size_t sent = 0;
  while (sent < s.size()) {
    const ssize_t n = ::send(fd, s.data() + sent, s.size() - sent, MSG_NOSIGNAL);
    if (n <= 0) return false;
    sent += static_cast<size_t>(n);
  }
  return true;
}

std::string status_line(int code) {
  switch (code) {
    case 200:
      return "200 OK";
    case 304:
      return "304 Not Modified";
    case 400:
      return "400 Bad Request";
    case 404:
      return "404 Not Found";
    case 405:
      return "405 Method Not Allowed";
    case 431:
      return "431 Request Header Fields Too Large";
    default:
      return "500 Internal Server Error";
  }
}

bool send_status(int fd, int code, bool keep_alive, const std::string& extra = "") {
  const std::string body = status_line(code) + "\n";
  return send_all(fd, fmt::format("HTTP/1.1 {}\r\nServer: relief\r\nContent-Type: text/plain\r\n"
                                  "Content-Length: {}\r\nConnection: {}\r\n{}\r\n{}",
                                  status_line(code), body.size(),
                                  keep_alive ? "keep-alive" : "close", extra, body));
}

std::string lower(std::string s) {
  for (char& c : s) c = static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
  return s;
}

// Parses the request head; nullopt for anything malformed.
std::optional<Request> parse(const std::string& head) {
  Request r;
  const size_t line_end = head.find("\r\n");
  const std::string line = head.substr(0, line_end);
  const size_t a = line.find(' '), b = line.rfind(' ');
  if (a == std::string::npos || b == a) return std::nullopt;
  r.method = line.substr(0, a);
  r.path = line.substr(a + 1, b - a - 1);
  r.version = line.substr(b + 1);
  if (r.version != "HTTP/1.1" && r.version != "HTTP/1.0") return std::nullopt;
  if (r.path.empty() || r.path.find(' ') != std::string::npos) return std::nullopt;
  r.keep_alive = r.version == "HTTP/1.1";
  size_t pos = line_end + 2;
  while (pos < head.size()) {
    const size_t end = head.find("\r\n", pos);
    if (end == std::string::npos || end == pos) break;
    const std::string field = head.substr(pos, end - pos);
    const size_t colon = field.find(':');
    if (colon == std::string::npos) return std::nullopt;
    const std::string name = lower(field.substr(0, colon));
    std::string value = field.substr(colon + 1);
    while (!value.empty() && value.front() == ' ') value.erase(0, 1);
    if (name == "connection") {
      const std::string v = lower(value);
      if (v == "close") r.keep_alive = false;
      if (v == "keep-alive") r.keep_alive = true;
    } else if (name == "if-none-match") {
      r.if_none_match = value;
    }
    pos = end + 2;
  }
  return r;
}

class Server final : public StoreServer {
 public:
  Server(std::filesystem::path root, int listener, int port, int threads)
      : root_(std::move(root)), listener_(listener), port_(port) {
    for (int i = 0; i < threads; ++i) workers_.emplace_back([this] { work(); });
    acceptor_ = std::thread([this] { accept_loop(); });
  }
  ~Server() override { stop(); }
  int port() const override { return port_; }

  void stop() override {
    if (stopping_.exchange(true)) return;
    ::shutdown(listener_, SHUT_RDWR);
    ::close(listener_);
    if (acceptor_.joinable()) acceptor_.join();
    {
      std::lock_guard lock(mutex_);
      for (int fd : queue_) ::close(fd);
      queue_.clear();
      for (int fd : active_) ::shutdown(fd, SHUT_RDWR);
    }
    ready_.notify_all();
    for (auto& t : workers_) t.join();
  }

 private:
  void accept_loop() {
    while (!stopping_) {
      const int fd = ::accept(listener_, nullptr, nullptr);
      if (fd < 0) {
        if (stopping_) return;
        continue;
      }
      timeval idle{kIdleSeconds, 0};
      ::setsockopt(fd, SOL_SOCKET, SO_RCVTIMEO, &idle, sizeof idle);
      const int one = 1;
      ::setsockopt(fd, IPPROTO_TCP, TCP_NODELAY, &one, sizeof one);
      std::lock_guard lock(mutex_);
      queue_.push_back(fd);
      ready_.notify_one();
    }
  }

  void work() {
    for (;;) {
      int fd = -1;
      {
        std::unique_lock lock(mutex_);
        ready_.wait(lock, [this] { return stopping_ || !queue_.empty(); });
        if (queue_.empty()) return;
        fd = queue_.front();
        queue_.pop_front();
        active_.push_back(fd);
      }
      serve_connection(fd);
      {
        std::lock_guard lock(mutex_);
        std::erase(active_, fd);
      }
      ::close(fd);
    }
  }

  void serve_connection(int fd) {
    std::string buffer;
    char chunk[4096];
    for (;;) {
      size_t end;
      while ((end = buffer.find("\r\n\r\n")) == std::string::npos) {
        if (buffer.size() > kMaxHeaderBytes) {
          send_status(fd, 431, false);
          return;
        }
        const ssize_t n = ::recv(fd, chunk, sizeof chunk, 0);
        if (n <= 0) return;  // closed, idle timeout or stop
        buffer.append(chunk, static_cast<size_t>(n));
      }
      if (end > kMaxHeaderBytes) {
        send_status(fd, 431, false);
        return;
      }
      const std::string head = buffer.substr(0, end);
      buffer.erase(0, end + 4);
      const auto request = parse(head);
      if (!request) {
        send_status(fd, 400, false);
        return;
      }
      if (!respond(fd, *request) || !request->keep_alive) return;
    }
  }

  bool respond(int fd, const Request& r) {
    const bool head = r.method == "HEAD";
    if (r.method != "GET" && !head)
      return send_status(fd, 405, r.keep_alive, "Allow: GET, HEAD\r\n");
    const auto file = store_file_for(r.path);
    if (!file) return send_status(fd, 404, r.keep_alive);
    const int in = ::open((root_ / *file).c_str(), O_RDONLY | O_NOFOLLOW | O_CLOEXEC);
    if (in < 0) return send_status(fd, 404, r.keep_alive);
    struct stat st {};
    if (::fstat(in, &st) != 0 || !S_ISREG(st.st_mode)) {
      ::close(in);
      return send_status(fd, 404, r.keep_alive);
    }
    // Store files are written once, atomically: size and modification time name a version.
    const std::string etag =
        fmt::format("\"{:x}-{:x}{:09x}\"", st.st_size, st.st_mtim.tv_sec, st.st_mtim.tv_nsec);
    const std::string common = fmt::format(
        "Server: relief\r\nETag: {}\r\nCache-Control: public, max-age=300\r\n"
        "Connection: {}\r\n",
        etag, r.keep_alive ? "keep-alive" : "close");
    if (!r.if_none_match.empty() && r.if_none_match == etag) {
      ::close(in);
      return send_all(fd, "HTTP/1.1 304 Not Modified\r\n" + common + "\r\n");
    }
    const char* type = file->ends_with(".json") ? "application/json" : "application/octet-stream";
    bool ok = send_all(
        fd, fmt::format("HTTP/1.1 200 OK\r\n{}Content-Type: {}\r\nContent-Length: {}\r\n\r\n",
                        common, type, st.st_size));
    off_t offset = 0;
    while (ok && !head && offset < st.st_size) {
      const ssize_t n = ::sendfile(fd, in, &offset, static_cast<size_t>(st.st_size - offset));
      if (n <= 0) ok = false;
    }
    ::close(in);
    return ok;
  }

  std::filesystem::path root_;
  int listener_, port_;
  std::atomic<bool> stopping_{false};
  std::mutex mutex_;
  std::condition_variable ready_;
  std::deque<int> queue_;
  std::vector<int> active_;
  std::vector<std::thread> workers_;
  std::thread acceptor_;
};

}  // namespace

std::optional<std::string> store_file_for(const std::string& path) {
  if (path.size() < 2 || path[0] != '/') return std::nullopt;
  const std::string rel = path.substr(1);
  if (rel == tiles::kManifestName) return rel;
  // Only canonical spellings: whatever parses must print back identically, so
  // "..", "//", "%2e", "./" and the like can never name a file.
  if (auto key = tiles::tile_key_from_relative_path(rel)) {
    if (tiles::tile_relative_path(*key) == rel) return rel;
    return std::nullopt;
  }
  for (int level = 0; level <= 30; ++level) {
    if (tiles::level_index_relative_path(level) == rel) return rel;
  }
  return std::nullopt;
}

Result<std::unique_ptr<StoreServer>> StoreServer::start(const ServeOptions& o) {
  std::error_code ec;
  if (!std::filesystem::is_regular_file(o.root / tiles::kManifestName, ec)) {
    return fail(fmt::format("{}: not a relief store (no manifest.json)", o.root.string()));
  }
  if (o.port < 0 || o.port > 65535) return fail(fmt::format("--port: {} is not a port", o.port));
  sockaddr_in address{};
  address.sin_family = AF_INET;
  address.sin_port = htons(static_cast<uint16_t>(o.port));
  if (::inet_pton(AF_INET, o.bind.c_str(), &address.sin_addr) != 1) {
    return fail(fmt::format("--bind: '{}' is not an IPv4 address", o.bind));
  }
  const int fd = ::socket(AF_INET, SOCK_STREAM | SOCK_CLOEXEC, 0);
  if (fd < 0) return fail(std::string("socket: ") + std::strerror(errno));
  const int one = 1;
  ::setsockopt(fd, SOL_SOCKET, SO_REUSEADDR, &one, sizeof one);
  if (::bind(fd, reinterpret_cast<sockaddr*>(&address), sizeof address) != 0 ||
      ::listen(fd, 256) != 0) {
    const std::string reason = std::strerror(errno);
    ::close(fd);
    return fail(fmt::format("{}:{}: cannot listen: {}", o.bind, o.port, reason));
  }
  socklen_t len = sizeof address;
  ::getsockname(fd, reinterpret_cast<sockaddr*>(&address), &len);
  return std::unique_ptr<StoreServer>(
      new Server(o.root, fd, ntohs(address.sin_port), std::max(1, o.threads)));
}

}  // namespace relief::serve
