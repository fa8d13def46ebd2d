#include "relief/serve/store_server.h"

#include <arpa/inet.h>
#include <fcntl.h>
#include <netinet/in.h>
#include <netinet/tcp.h>
#include <sys/epoll.h>
#include <sys/eventfd.h>
#include <sys/resource.h>
#include <sys/socket.h>
#include <unistd.h>

#include <algorithm>
#include <atomic>
#include <cstring>
#include <mutex>
#include <thread>
#include <unordered_map>
#include <vector>

#include <fmt/format.h>

#include "answer.h"
#include "generation_pool.h"
#include "http_request.h"
#include "relief/tiles/store_layout.h"

namespace relief::serve {
namespace {

using Clock = std::chrono::steady_clock;
constexpr size_t kFileChunkBytes = 256 * 1024;
constexpr int kWaitMilliseconds = 100;  // with connections open, deadlines are checked this often
constexpr auto kSweepInterval = std::chrono::milliseconds(50);

// One client connection, owned by the event loop that accepted it. It reads
// a request head (before its read deadline), then writes the answer (making
// progress before each write deadline), then reads the next head.
struct Connection {
  int fd = -1;
  std::string in;   // received bytes not yet parsed
  std::string out;  // bytes to send: an answer's head, then file chunks
  size_t out_sent = 0;
  int file = -1;  // the answer's file, read chunk by chunk
  uint64_t file_pos = 0, file_end = 0;
  bool writing = false;      // an answer is in progress
  bool close_after = false;  // end the connection once the answer is sent
  bool peer_done = false;    // the client shut its side: answer what is buffered, then end
  // A generated answer is being made on the pool (ServeOptions::generate):
  // nothing is read or written until it comes back.
  bool waiting = false;
  uint64_t serial = 0;  // tells this connection from a later one on the same descriptor
  Clock::time_point deadline;
};

enum class Progress { blocked, done, closed };

// Over the limit with no idle connection to close: say so at once (best
// effort, never waiting) rather than queueing.
void refuse_busy(int fd) {
  const Answer busy = status_answer(503, false);
  [[maybe_unused]] const ssize_t sent =
      ::send(fd, busy.head.data(), busy.head.size(), MSG_NOSIGNAL | MSG_DONTWAIT);
  ::close(fd);
}

class Server;

// An epoll loop on its own thread: accepts from the shared listener (woken
// exclusively, so one loop takes each burst) and serves its connections
// without blocking on any of them.
class Loop {
 public:
  explicit Loop(Server& server);
  ~Loop();
  void run();
  void wake() {
    const uint64_t one = 1;
    [[maybe_unused]] const ssize_t n = ::write(wake_fd_, &one, sizeof one);
  }

  // Takes a connection accepted by another loop that had no idle one to close.
  void hand_over(int fd) {
    {
      std::lock_guard lock(handed_mutex_);
      handed_.push_back(fd);
    }
    wake();
  }
  size_t size() const { return size_.load(std::memory_order_relaxed); }

  // An answer made on the pool for connection `fd` of `serial` (any thread).
  void deliver(int fd, uint64_t serial, Answer answer) {
    {
      std::lock_guard lock(handed_mutex_);
      made_.push_back({fd, serial, std::move(answer)});
    }
    wake();
  }

 private:
  struct Made {
    int fd;
    uint64_t serial;
    Answer answer;
  };
  // Starts the answer to `request`, or hands it to the generation pool
  // (false: the answer comes later, take_made()).
  bool answer(Connection& c, const Request& request, Clock::time_point now);
  void take_made(Clock::time_point now);
  void accept_some(Clock::time_point now);
  void on_event(Connection& c, uint32_t events, Clock::time_point now);
  void read_some(Connection& c, Clock::time_point now);
  // Answers every complete request head buffered; false if the connection ended.
  bool serve_buffered(Connection& c, Clock::time_point now);
  void start_answer(Connection& c, Answer answer, Clock::time_point now);
  Progress write_some(Connection& c, Clock::time_point now);
  bool fill_from_file(Connection& c);
  void watch(Connection& c, uint32_t events, int op = EPOLL_CTL_MOD);
  void close_connection(Connection& c);
  void sweep(Clock::time_point now);
  void adopt(int fd, Clock::time_point now);
  // Over the connection limit: closes this loop's longest-idle connection (no
  // answer in progress, no request begun); false if it has none.
  bool evict_idle();
  void take_handed(Clock::time_point now);

  Server& server_;
  int epoll_fd_ = -1, wake_fd_ = -1;
  std::unordered_map<int, Connection> connections_;
  std::atomic<size_t> size_{0};  // connections_.size(), for other loops to read
  std::mutex handed_mutex_;      // guards handed_ and made_
  std::vector<int> handed_;
  std::vector<Made> made_;
  uint64_t next_serial_ = 0;
};

class Server final : public StoreServer {
 public:
  Server(const ServeOptions& o, int listener, int port)
      : options_(o), listener_(listener), port_(port) {
    if (!options_.clock) options_.clock = [] { return Clock::now(); };
    // Each connection holds a socket and, while answering, a file: stay below
    // the descriptor limit, so accept() never fails for want of one.
    rlimit files{};
    if (::getrlimit(RLIMIT_NOFILE, &files) == 0 && files.rlim_cur != RLIM_INFINITY) {
      const auto spare = static_cast<int>(std::min<rlim_t>(files.rlim_cur, 1 << 20) / 2) - 16;
      options_.max_connections = std::max(1, std::min(options_.max_connections, spare));
    }
    if (options_.generate) {
      const int threads = options_.generate_threads > 0
                              ? options_.generate_threads
                              : static_cast<int>(std::thread::hardware_concurrency());
      pool_ = std::make_unique<GenerationPool>(threads);
    }
    for (int i = 0; i < std::max(1, o.threads); ++i)
      loops_.push_back(std::make_unique<Loop>(*this));
    for (auto& loop : loops_) threads_.emplace_back([l = loop.get()] { l->run(); });
  }
  ~Server() override { stop(); }
  int port() const override { return port_; }

  void stop() override {
    if (stopping_.exchange(true)) return;
    if (pool_) pool_->stop();  // before the loops it delivers to go
    for (auto& loop : loops_) loop->wake();
    for (auto& t : threads_) t.join();
    loops_.clear();
    ::close(listener_);
  }

  // The loop with the most connections other than `self` (the likeliest to
  // have an idle one), or nullptr.
  Loop* fullest_other(const Loop* self) const {
    Loop* fullest = nullptr;
    for (const auto& loop : loops_) {
      if (loop.get() != self && (!fullest || loop->size() > fullest->size())) fullest = loop.get();
    }
    return fullest;
  }

  ServeOptions options_;
  int listener_, port_;
  std::atomic<bool> stopping_{false};
  std::atomic<int> open_connections_{0};
  std::unique_ptr<GenerationPool> pool_;  // with a generator only

 private:
  std::vector<std::unique_ptr<Loop>> loops_;
  std::vector<std::thread> threads_;
};

Loop::Loop(Server& server) : server_(server) {
  epoll_fd_ = ::epoll_create1(EPOLL_CLOEXEC);
  wake_fd_ = ::eventfd(0, EFD_NONBLOCK | EFD_CLOEXEC);
  epoll_event e{};
  e.events = EPOLLIN;
  e.data.fd = wake_fd_;
  ::epoll_ctl(epoll_fd_, EPOLL_CTL_ADD, wake_fd_, &e);
  e.events = EPOLLIN | EPOLLEXCLUSIVE;
  e.data.fd = server_.listener_;
  ::epoll_ctl(epoll_fd_, EPOLL_CTL_ADD, server_.listener_, &e);
}

Loop::~Loop() {
  for (int fd : handed_) ::close(fd);  // handed over while the server stopped
  ::close(epoll_fd_);
  ::close(wake_fd_);
}

void Loop::run() {
  epoll_event events[128];
  auto last_sweep = Clock::now();
  while (!server_.stopping_) {
    // With no connection there is no deadline: sleep until a client or stop() comes.
    const int wait = connections_.empty() ? -1 : kWaitMilliseconds;
    const int n = ::epoll_wait(epoll_fd_, events, 128, wait);
    const auto now = server_.options_.clock();
    for (int i = 0; i < n; ++i) {
      const int fd = events[i].data.fd;
      if (fd == wake_fd_) {  // stop() or another loop's hand-over woke us
        uint64_t count = 0;
        [[maybe_unused]] const ssize_t r = ::read(wake_fd_, &count, sizeof count);
        take_handed(now);
        take_made(now);
        continue;
      }
      if (fd == server_.listener_) {
        accept_some(now);
        continue;
      }
      const auto it = connections_.find(fd);
      if (it != connections_.end()) on_event(it->second, events[i].events, now);
    }
    // The sweep runs on real time; deadlines are measured on the given clock.
    if (Clock::now() - last_sweep >= kSweepInterval) {
      sweep(now);
      last_sweep = Clock::now();
    }
  }
  while (!connections_.empty()) close_connection(connections_.begin()->second);
}

void Loop::accept_some(Clock::time_point now) {
  for (int i = 0; i < 64; ++i) {
    const int fd = ::accept4(server_.listener_, nullptr, nullptr, SOCK_NONBLOCK | SOCK_CLOEXEC);
    if (fd < 0) return;  // none left (EAGAIN), or out of descriptors: the limit should prevent it
    if (server_.open_connections_.fetch_add(1) >= server_.options_.max_connections &&
        !evict_idle()) {
      // Idle connections elsewhere (1 024 silent sockets of one client must
      // not lock everyone else out until their deadlines): the loop holding
      // the most decides.
      if (Loop* other = server_.fullest_other(this); other && other->size() > 0) {
        other->hand_over(fd);
        continue;
      }
      --server_.open_connections_;
      refuse_busy(fd);
      continue;
    }
    adopt(fd, now);
  }
}

void Loop::adopt(int fd, Clock::time_point now) {
  const int one = 1;
  ::setsockopt(fd, IPPROTO_TCP, TCP_NODELAY, &one, sizeof one);
  Connection& c = connections_[fd];
  c.fd = fd;
  c.serial = ++next_serial_;
  c.deadline = now + server_.options_.read_timeout;
  watch(c, EPOLLIN, EPOLL_CTL_ADD);
  size_.store(connections_.size(), std::memory_order_relaxed);
}

bool Loop::evict_idle() {
  Connection* oldest = nullptr;
  for (auto& [fd, c] : connections_) {
    if (!c.writing && !c.waiting && c.in.empty() && (!oldest || c.deadline < oldest->deadline)) {
      oldest = &c;
    }
  }
  if (!oldest) return false;
  close_connection(*oldest);
  return true;
}

void Loop::take_handed(Clock::time_point now) {
  std::vector<int> handed;
  {
    std::lock_guard lock(handed_mutex_);
    handed.swap(handed_);
  }
  // Each was counted in open_connections_ by the loop that accepted it.
  for (int fd : handed) {
    if (evict_idle()) {
      adopt(fd, now);
    } else {
      --server_.open_connections_;
      refuse_busy(fd);
    }
  }
}

void Loop::on_event(Connection& c, uint32_t events, Clock::time_point now) {
  if (now >= c.deadline) return close_connection(c);
  if (c.waiting) {  // watched for errors only until the answer comes
    if (events & (EPOLLERR | EPOLLHUP)) close_connection(c);
    return;
  }
  if (c.writing) {
    if (events & (EPOLLOUT | EPOLLERR | EPOLLHUP)) {
      if (write_some(c, now) == Progress::done && serve_buffered(c, now)) {
        watch(c, c.writing ? EPOLLOUT : EPOLLIN);
      }
    }
    return;
  }
  read_some(c, now);
}

void Loop::read_some(Connection& c, Clock::time_point now) {
  char buffer[16384];
  while (c.in.size() <= kMaxRequestHeadBytes) {
    const ssize_t n = ::recv(c.fd, buffer, sizeof buffer, 0);
    if (n > 0) {
      c.in.append(buffer, static_cast<size_t>(n));
      // A short read drained the socket: skip the recv that would say EAGAIN
      // (level-triggered epoll reports anything that arrives later).
      if (static_cast<size_t>(n) < sizeof buffer) break;
      continue;
    }
    if (n == 0) {
      c.peer_done = true;
      break;
    }
    if (errno == EAGAIN || errno == EWOULDBLOCK) break;
    if (errno == EINTR) continue;
    return close_connection(c);
  }
  if (serve_buffered(c, now) && c.writing) watch(c, EPOLLOUT);
}

bool Loop::serve_buffered(Connection& c, Clock::time_point now) {
  while (!c.writing && !c.waiting) {
    const size_t end = c.in.find("\r\n\r\n");
    if (end == std::string::npos || end + 4 > kMaxRequestHeadBytes) {
      if (c.in.size() > kMaxRequestHeadBytes) {
        start_answer(c, status_answer(431, false), now);
      } else if (c.peer_done) {
        close_connection(c);
        return false;
      } else {
        return true;  // wait for the rest of the head
      }
    } else {
      const auto request = parse_request_head(std::string_view(c.in).substr(0, end + 4));
      c.in.erase(0, end + 4);
      if (!request) {
        start_answer(c, status_answer(400, false), now);
      } else if (!answer(c, *request, now)) {
        return true;  // made on the pool: its answer comes later
      }
    }
    if (write_some(c, now) == Progress::closed) return false;
  }
  return true;
}

bool Loop::answer(Connection& c, const Request& request, Clock::time_point now) {
  const ServeOptions& o = server_.options_;
  if (!server_.pool_ || (request.method != "GET" && request.method != "HEAD") ||
      store_file_for(request.target)) {
    start_answer(c, answer_request(o.root, request, o.share_index, o.share_count, o.generate), now);
    return true;
  }
  if (o.generate_at_once) {  // made already (a cached tile): no need for the pool
    if (auto made = o.generate_at_once(request.target)) {
      const Generator given = [&made](std::string_view) { return std::move(made); };
      start_answer(c, answer_request(o.root, request, o.share_index, o.share_count, given), now);
      return true;
    }
  }
  c.waiting = true;
  c.deadline = now + o.write_timeout;  // the answer must come (and then progress) in time
  watch(c, 0);                         // errors and hang-ups only
  server_.pool_->submit([this, &o, fd = c.fd, serial = c.serial, request] {
    deliver(fd, serial, answer_request(o.root, request, o.share_index, o.share_count, o.generate));
  });
  return true;
}

void Loop::take_made(Clock::time_point now) {
  std::vector<Made> made;
  {
    std::lock_guard lock(handed_mutex_);
    made.swap(made_);
  }
  for (Made& m : made) {
    const auto it = connections_.find(m.fd);
    if (it == connections_.end() || it->second.serial != m.serial || !it->second.waiting) {
      if (m.answer.file >= 0) ::close(m.answer.file);  // its connection ended meanwhile
      continue;
    }
    Connection& c = it->second;
    c.waiting = false;
    start_answer(c, std::move(m.answer), now);
    const Progress p = write_some(c, now);
    if (p == Progress::closed || (p == Progress::done && !serve_buffered(c, now))) continue;
    if (!c.waiting) watch(c, c.writing ? EPOLLOUT : EPOLLIN);
  }
}

void Loop::start_answer(Connection& c, Answer answer, Clock::time_point now) {
  c.writing = true;
  c.out = std::move(answer.head);
  c.out_sent = 0;
  c.file = answer.file;
  c.file_pos = answer.offset;
  c.file_end = answer.offset + answer.length;
  c.close_after = answer.close || c.peer_done;
  c.deadline = now + server_.options_.write_timeout;
  if (c.file >= 0 && !fill_from_file(c)) c.close_after = true;
}

// Appends the file's next chunk to the output; false if the file ended early.
bool Loop::fill_from_file(Connection& c) {
  const size_t want =
      static_cast<size_t>(std::min<uint64_t>(kFileChunkBytes, c.file_end - c.file_pos));
  const size_t old = c.out.size();
  c.out.resize(old + want);
  const ssize_t n = ::pread(c.file, c.out.data() + old, want, static_cast<off_t>(c.file_pos));
  if (n <= 0) {
    c.out.resize(old);
    c.file_pos = c.file_end;  // the file shrank under us: end the connection after what we have
    return false;
  }
  c.out.resize(old + static_cast<size_t>(n));
  c.file_pos += static_cast<uint64_t>(n);
  return true;
}

Progress Loop::write_some(Connection& c, Clock::time_point now) {
  for (;;) {
    if (c.out_sent == c.out.size()) {
      c.out.clear();
      c.out_sent = 0;
      if (c.file_pos < c.file_end) {
        if (!fill_from_file(c)) c.close_after = true;
        continue;
      }
      if (c.file >= 0) ::close(c.file);
      c.file = -1;
      if (c.close_after) {
        close_connection(c);
        return Progress::closed;
      }
      c.writing = false;
      c.deadline = now + server_.options_.read_timeout;
      return Progress::done;
    }
    // MSG_NOSIGNAL: a client that hung up is an error value here, never a SIGPIPE.
    const ssize_t n =
        ::send(c.fd, c.out.data() + c.out_sent, c.out.size() - c.out_sent, MSG_NOSIGNAL);
    if (n > 0) {
      c.out_sent += static_cast<size_t>(n);
      c.deadline = now + server_.options_.write_timeout;  // progress moves the deadline
      continue;
    }
    if (n < 0 && (errno == EAGAIN || errno == EWOULDBLOCK)) return Progress::blocked;
    if (n < 0 && errno == EINTR) continue;
    close_connection(c);
    return Progress::closed;
  }
}

void Loop::watch(Connection& c, uint32_t events, int op) {
  epoll_event e{};
  e.events = events;
  e.data.fd = c.fd;
  ::epoll_ctl(epoll_fd_, op, c.fd, &e);
}

void Loop::close_connection(Connection& c) {
  const int fd = c.fd;
  if (c.file >= 0) ::close(c.file);
  ::close(fd);  // also leaves the epoll set
  --server_.open_connections_;
  connections_.erase(fd);  // c is gone from here on
  size_.store(connections_.size(), std::memory_order_relaxed);
}

void Loop::sweep(Clock::time_point now) {
  std::vector<int> expired;
  for (const auto& [fd, c] : connections_) {
    if (now >= c.deadline) expired.push_back(fd);
  }
  for (int fd : expired) close_connection(connections_.at(fd));
}

}  // namespace

bool in_share(const std::string& file, uint32_t index, uint32_t count) {
  const auto key = tiles::tile_key_from_relative_path(file);
  return !key || key->morton() % count == index;
}

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
  if (o.max_connections < 1) return fail("serve: the connection limit must be at least 1");
  if (o.share_count < 1 || o.share_index >= o.share_count) {
    return fail(fmt::format("--share: {}/{} is not a share i/n with 0 <= i < n", o.share_index,
                            o.share_count));
  }
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
      ::listen(fd, SOMAXCONN) != 0) {
    const std::string reason = std::strerror(errno);
    ::close(fd);
    return fail(fmt::format("{}:{}: cannot listen: {}", o.bind, o.port, reason));
  }
  socklen_t len = sizeof address;
  ::getsockname(fd, reinterpret_cast<sockaddr*>(&address), &len);
  ::fcntl(fd, F_SETFL, O_NONBLOCK);  // the loops accept until EAGAIN
  return std::unique_ptr<StoreServer>(new Server(o, fd, ntohs(address.sin_port)));
}

}  // namespace relief::serve
