// `relief serve` against the clients a hostile probe used: clients that hang
// up before the answer (SIGPIPE), send a byte at a time, never read, hold
// more keep-alive connections than there are threads or more connections
// than the limit, and a FIFO planted at a tile path. Deadlines run on an
// injected clock that the tests move forward, so nothing waits for them.
#include <gtest/gtest.h>

#include <signal.h>
#include <sys/socket.h>
#include <sys/stat.h>
#include <sys/wait.h>
#include <unistd.h>

#include <atomic>
#include <chrono>
#include <condition_variable>
#include <fstream>
#include <latch>
#include <mutex>
#include <optional>
#include <string_view>
#include <thread>
#include <vector>

#include "http_client.h"
#include "relief/serve/store_server.h"
#include "relief/tiles/store_layout.h"
#include "servers.h"
#include "test_support.h"

namespace relief::testing {
namespace {
namespace fs = std::filesystem;
using namespace std::chrono_literals;

// Larger than a loopback socket's send and receive buffers together, so the
// server is still writing when a client hangs up or stops reading.
constexpr size_t kBigFileBytes = 16u << 20;

// The server's clock: the real one plus an offset the test moves forward.
struct MovableClock {
  std::atomic<int64_t> offset_ms{0};
  std::chrono::steady_clock::time_point now() const {
    return std::chrono::steady_clock::now() + std::chrono::milliseconds(offset_ms.load());
  }
  void advance(std::chrono::milliseconds d) { offset_ms += d.count(); }
};

class HostileClientsTest : public ::testing::Test {
 protected:
  static void SetUpTestSuite() {
    dir_ = new ScratchDir("serve_hostile");
    root_ = dir_->path() / "store";
    const std::string big = tiles::tile_relative_path({5, 3, 7});
    const std::string fifo = tiles::tile_relative_path({5, 1, 1});
    fs::create_directories((root_ / big).parent_path());
    fs::create_directories((root_ / fifo).parent_path());
    std::ofstream(root_ / "manifest.json") << "{}";
    std::ofstream(root_ / big) << std::string(kBigFileBytes, 'x');
    ASSERT_EQ(::mkfifo((root_ / fifo).c_str(), 0600), 0);
    big_path_ = "/" + big;
    fifo_path_ = "/" + fifo;
  }
  static void TearDownTestSuite() { delete dir_; }

  // An in-process server on a free port with short-lived threads and
  // deadlines far away unless the clock is moved.
  std::unique_ptr<serve::StoreServer> start(serve::ServeOptions o = {}, int loops = 2) {
    o.root = root_;
    o.port = 0;
    o.threads = loops;
    o.clock = [this] { return clock_.now(); };
    auto server = serve::StoreServer::start(o);
    EXPECT_TRUE(server) << server.error().message;
    return std::move(*server);
  }
  static std::string get_request(const std::string& path) {
    return "GET " + path + " HTTP/1.1\r\nHost: x\r\n\r\n";
  }

  static inline ScratchDir* dir_ = nullptr;
  static inline fs::path root_;
  static inline std::string big_path_, fifo_path_;
  MovableClock clock_;
};

TEST_F(HostileClientsTest, ClientsHangingUpBeforeTheAnswerDoNotKillTheServer) {
  auto server = start();
  for (int i = 0; i < 40; ++i) {
    const int fd = connect_client(server->port());
    const std::string req = get_request(big_path_);
    ::send(fd, req.data(), req.size(), MSG_NOSIGNAL);
    ::close(fd);  // unread data: the server's next write meets a reset
  }
  // Still alive and serving (a SIGPIPE would have ended this process).
  EXPECT_EQ(get(server->port(), big_path_).body.size(), kBigFileBytes);
  EXPECT_EQ(get(server->port(), "/manifest.json").status, 200);
}

TEST_F(HostileClientsTest, SlowClientsDoNotDelayOthers) {
  auto server = start();
  std::vector<int> slow;
  for (int i = 0; i < 200; ++i) {
    slow.push_back(connect_client(server->port()));
    ASSERT_GE(slow.back(), 0);
    ::send(slow.back(), "GET /manifest.json HTTP/1.1\r\nHo", 31, MSG_NOSIGNAL);
  }
  EXPECT_EQ(get(server->port(), "/manifest.json").status, 200);
  for (int fd : slow) ::close(fd);
}

TEST_F(HostileClientsTest, TheReadDeadlineClosesSlowAndIdleConnections) {
  serve::ServeOptions o;
  o.read_timeout = 1h;
  auto server = start(o);
  const int port = server->port();
  // A client sending its head a byte now and then: bytes do not extend the deadline.
  const int slow = connect_client(port);
  ::send(slow, "G", 1, MSG_NOSIGNAL);
  // A keep-alive connection left idle after one answer.
  const int idle = connect_client(port);
  const std::string req = get_request("/manifest.json");
  ::send(idle, req.data(), req.size(), MSG_NOSIGNAL);
  EXPECT_EQ(read_response(idle).status, 200);
  for (int i = 0; i < 3; ++i) {
    clock_.advance(25min);
    ::send(slow, "E", 1, MSG_NOSIGNAL);
  }
  clock_.advance(25min);
  EXPECT_TRUE(closed_by_server(slow));
  EXPECT_TRUE(closed_by_server(idle));
  ::close(slow);
  ::close(idle);
  // New connections have deadlines of their own.
  EXPECT_EQ(get(port, "/manifest.json").status, 200);
}

TEST_F(HostileClientsTest, ClientsThatNeverReadDoNotBlockOthersAndAreDropped) {
  serve::ServeOptions o;
  o.write_timeout = 1h;
  auto server = start(o);
  std::vector<int> stuck;
  for (int i = 0; i < 16; ++i) {
    stuck.push_back(connect_client(server->port()));
    const std::string req = get_request(big_path_);
    ::send(stuck.back(), req.data(), req.size(), MSG_NOSIGNAL);
  }
  EXPECT_EQ(get(server->port(), "/manifest.json").status, 200);
  // Past the write deadline they are dropped: reading now ends before the file does.
  clock_.advance(2h);
  for (int fd : stuck) {
    EXPECT_TRUE(closed_by_server(fd));
    ::close(fd);
  }
}

TEST_F(HostileClientsTest, KeepAliveClientsBeyondTheThreadCountAreAllServed) {
  auto server = start();
  constexpr int kClients = 50, kRequests = 20;
  std::atomic<int> good{0};
  std::latch all_done(kClients);
  std::vector<std::thread> clients;
  for (int c = 0; c < kClients; ++c) {
    clients.emplace_back([&] {
      const int fd = connect_client(server->port());
      const std::string req = get_request("/manifest.json");
      for (int i = 0; i < kRequests; ++i) {
        ::send(fd, req.data(), req.size(), MSG_NOSIGNAL);
        if (read_response(fd).body != "{}") break;
        ++good;
      }
      all_done.arrive_and_wait();  // every connection stays open until all are served
      ::close(fd);
    });
  }
  for (auto& t : clients) t.join();
  EXPECT_EQ(good.load(), kClients * kRequests);
}

// Busy connections (an answer in progress: a large file the client does not
// read) hold their slots: one more client is refused at once.
TEST_F(HostileClientsTest, ConnectionsBeyondTheLimitAreRefusedAtOnce) {
  serve::ServeOptions o;
  o.max_connections = 8;
  auto server = start(o);
  std::vector<int> held;
  const std::string req = get_request(big_path_);
  for (int i = 0; i < 8; ++i) {
    held.push_back(connect_client(server->port()));
    ::send(held.back(), req.data(), req.size(), MSG_NOSIGNAL);
    char first = 0;  // the answer has begun: the server is writing it
    ASSERT_EQ(::recv(held.back(), &first, 1, 0), 1);
  }
  const int extra = connect_client(server->port());
  EXPECT_EQ(read_response(extra).status, 503);
  EXPECT_TRUE(closed_by_server(extra));
  ::close(extra);
  // A slot freed is a slot available again (once the server has seen the close).
  ::close(held.back());
  held.pop_back();
  int status = 0;
  for (int attempt = 0; attempt < 200 && status != 200; ++attempt) {
    status = get(server->port(), "/manifest.json").status;
    if (status != 200) std::this_thread::sleep_for(10ms);
  }
  EXPECT_EQ(status, 200);
  for (int fd : held) ::close(fd);
}

// Idle connections (keep-alive after an answer, or opened and silent) make
// room for a newcomer, the longest idle first: a client holding the whole
// limit open does not lock others out until the read deadline.
TEST_F(HostileClientsTest, IdleConnectionsMakeRoomForNewClients) {
  serve::ServeOptions o;
  o.max_connections = 8;
  auto server = start(o);
  std::vector<int> idle;
  const std::string req = get_request("/manifest.json");
  for (int i = 0; i < 4; ++i) {  // answered, then kept alive
    idle.push_back(connect_client(server->port()));
    ::send(idle.back(), req.data(), req.size(), MSG_NOSIGNAL);
    ASSERT_EQ(read_response(idle.back()).status, 200);
  }
  for (int i = 0; i < 4; ++i) idle.push_back(connect_client(server->port()));  // silent
  for (int round = 0; round < 20; ++round) {
    EXPECT_EQ(get(server->port(), "/manifest.json").status, 200) << "round " << round;
  }
  // Idle ones were closed for them (before the first newcomer was answered).
  int closed = 0;
  for (int fd : idle) {
    char byte = 0;
    closed += ::recv(fd, &byte, 1, MSG_DONTWAIT) == 0;
    ::close(fd);
  }
  EXPECT_GE(closed, 1);
}

// The `relief serve` process: a FIFO at a tile path is not a file to serve (it
// used to block a worker in open()), and SIGTERM still stops the server.
TEST_F(HostileClientsTest, AFifoAtATilePathIsRefusedAndSigtermStillStops) {
  const int port = free_port();
  const int pid = spawn_relief({"serve", root_.string(), "--port", std::to_string(port)});
  wait_for(port);
  EXPECT_EQ(get(port, fifo_path_).status, 404);
  EXPECT_EQ(get(port, "/manifest.json").status, 200);
  ::kill(pid, SIGTERM);
  int status = -1;
  for (int i = 0; i < 500 && ::waitpid(pid, &status, WNOHANG) == 0; ++i) {
    std::this_thread::sleep_for(20ms);
  }
  if (::waitpid(pid, nullptr, WNOHANG) == 0) {
    ::kill(pid, SIGKILL);
    ::waitpid(pid, &status, 0);
    FAIL() << "relief serve did not stop on SIGTERM";
  }
  EXPECT_TRUE(WIFEXITED(status) && WEXITSTATUS(status) == 0);
}

// A generator that holds "/slow" until released and answers "/fast" at once,
// like a web tile being made beside one already cached.
struct HeldGenerator {
  std::mutex mutex;
  std::condition_variable released_cv;
  bool released = false;
  std::atomic<int> slow_started{0};

  serve::Generator generator() {
    return [this](std::string_view target) -> std::optional<serve::GeneratedAnswer> {
      if (target == "/fast") return serve::GeneratedAnswer{"text/plain", "", "fast"};
      if (target != "/slow") return std::nullopt;
      ++slow_started;
      std::unique_lock lock(mutex);
      released_cv.wait(lock, [this] { return released; });
      return serve::GeneratedAnswer{"text/plain", "", "slow"};
    };
  }
  void release() {
    {
      std::lock_guard lock(mutex);
      released = true;
    }
    released_cv.notify_all();
  }
  void wait_started() const {
    for (int i = 0; i < 500 && slow_started == 0; ++i) std::this_thread::sleep_for(10ms);
  }
};

// Answers made by the generator run on its own threads: while one is being
// made, the one event loop goes on serving store files and other generated
// answers, and the connection that asked gets it once made.
TEST_F(HostileClientsTest, AnAnswerBeingGeneratedDoesNotHoldUpTheLoop) {
  HeldGenerator held;
  serve::ServeOptions o;
  o.generate = held.generator();
  o.generate_threads = 2;
  auto server = start(o, 1);  // one loop: the one that took /slow must serve the rest
  const int waiting = connect_client(server->port());
  const std::string slow = get_request("/slow");
  ASSERT_EQ(::send(waiting, slow.data(), slow.size(), MSG_NOSIGNAL),
            static_cast<ssize_t>(slow.size()));
  held.wait_started();
  ASSERT_EQ(held.slow_started, 1);
  for (int i = 0; i < 3; ++i) {  // answered while /slow is held
    EXPECT_EQ(get(server->port(), "/manifest.json").status, 200);
    const Response fast = get(server->port(), "/fast");
    EXPECT_EQ(fast.status, 200);
    EXPECT_EQ(fast.body, "fast");
  }
  held.release();
  const Response r = read_response(waiting);
  EXPECT_EQ(r.status, 200);
  EXPECT_EQ(r.body, "slow");
  ::close(waiting);
}

// Requests sent together on one connection are answered in their order, a
// generated one first included; a client that hangs up while its answer is
// made costs nothing, and the server stops with generation under way.
TEST_F(HostileClientsTest, GeneratedAnswersKeepTheOrderOfAConnectionsRequests) {
  HeldGenerator held;
  serve::ServeOptions o;
  o.generate = held.generator();
  o.generate_threads = 1;
  auto server = start(o);
  const int fd = connect_client(server->port());
  const std::string both =
      get_request("/slow") + get_request("/manifest.json") + get_request("/fast");
  ASSERT_EQ(::send(fd, both.data(), both.size(), MSG_NOSIGNAL), static_cast<ssize_t>(both.size()));
  held.wait_started();
  std::this_thread::sleep_for(50ms);  // the loop has the other two and must hold them back
  held.release();
  // The three answers, read as one stream (they may arrive in one segment).
  std::string answers;
  char buffer[4096];
  while (answers.find("\r\n\r\nfast") == std::string::npos) {
    const ssize_t n = ::recv(fd, buffer, sizeof buffer, 0);  // times out after 5 s
    if (n <= 0) break;
    answers.append(buffer, static_cast<size_t>(n));
  }
  const size_t slow_at = answers.find("\r\n\r\nslow"), manifest_at = answers.find("\r\n\r\n{}"),
               fast_at = answers.find("\r\n\r\nfast");
  ASSERT_NE(fast_at, std::string::npos) << answers;
  EXPECT_LT(slow_at, manifest_at) << answers;
  EXPECT_LT(manifest_at, fast_at) << answers;
  ::close(fd);

  HeldGenerator again;
  o.generate = again.generator();
  o.generate_threads = 2;  // one held by /slow, one for /fast
  auto second_server = start(o);
  const int gone = connect_client(second_server->port());
  const std::string slow = get_request("/slow");
  ::send(gone, slow.data(), slow.size(), MSG_NOSIGNAL);
  again.wait_started();
  ::close(gone);  // hangs up before its answer is made
  EXPECT_EQ(get(second_server->port(), "/fast").body, "fast");
  again.release();
  EXPECT_EQ(get(second_server->port(), "/manifest.json").status, 200);
  second_server->stop();
}

// The deadlines and the connection limit are the user's to set: a short read
// deadline closes an idle connection of the `relief serve` process, and
// impossible values are one-line errors naming the option.
TEST_F(HostileClientsTest, DeadlinesAndTheLimitAreCommandLineOptions) {
  for (const auto& [option, value] :
       {std::pair{"--read-timeout", "0"}, std::pair{"--write-timeout", "-1"},
        std::pair{"--read-timeout", "nan"}, std::pair{"--max-connections", "0"}}) {
    const RunResult r = run_relief({"serve", root_.string(), "--port", "0", option, value});
    EXPECT_NE(r.exit_code, 0) << option << " " << value;
    EXPECT_NE(r.err.find(option), std::string::npos) << r.err;
    EXPECT_EQ(r.err.find('\n'), r.err.size() - 1) << r.err;
  }
  const int port = free_port();
  const int pid = spawn_relief({"serve", root_.string(), "--port", std::to_string(port),
                                "--read-timeout", "0.2", "--max-connections", "8"});
  wait_for(port);
  const int idle = connect_client(port);
  EXPECT_TRUE(closed_by_server(idle));  // after 0.2 s, long before the client's own 5 s
  ::close(idle);
  EXPECT_EQ(get(port, "/manifest.json").status, 200);
  ::kill(pid, SIGTERM);
  ::waitpid(pid, nullptr, 0);
}

}  // namespace
}  // namespace relief::testing
