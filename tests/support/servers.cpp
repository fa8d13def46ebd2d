#include "servers.h"

#include <gtest/gtest.h>

#include <arpa/inet.h>
#include <netinet/in.h>
#include <sys/socket.h>
#include <unistd.h>

#include <chrono>
#include <cstdio>
#include <fstream>
#include <thread>

namespace relief::testing {

std::string read_request_path(int fd) {
  std::string req;
  char buf[4096];
  while (req.find("\r\n\r\n") == std::string::npos) {
    const ssize_t n = ::recv(fd, buf, sizeof buf, 0);
    if (n <= 0) break;
    req.append(buf, static_cast<size_t>(n));
  }
  const size_t a = req.find(' '), b = req.find(' ', a + 1);
  return a == std::string::npos ? "" : req.substr(a + 2, b - a - 2);
}

int free_port() {
  const int fd = ::socket(AF_INET, SOCK_STREAM, 0);
  sockaddr_in a{};
  a.sin_family = AF_INET;
  a.sin_addr.s_addr = htonl(INADDR_LOOPBACK);
  ::bind(fd, reinterpret_cast<sockaddr*>(&a), sizeof a);
  socklen_t len = sizeof a;
  ::getsockname(fd, reinterpret_cast<sockaddr*>(&a), &len);
  ::close(fd);
  return ntohs(a.sin_port);
}

int connect_to(int port) {
  const int fd = ::socket(AF_INET, SOCK_STREAM, 0);
  sockaddr_in a{};
  a.sin_family = AF_INET;
  a.sin_port = htons(static_cast<uint16_t>(port));
  a.sin_addr.s_addr = htonl(INADDR_LOOPBACK);
  if (::connect(fd, reinterpret_cast<sockaddr*>(&a), sizeof a) != 0) {
    ::close(fd);
    return -1;
  }
  return fd;
}

void wait_for(int port) {
  // A safety bound only (60 s): a loaded machine (sanitizers, 2 cores) may take
  // seconds to start a server; a server that never listens still fails.
  for (int i = 0; i < 3000; ++i) {
    const int fd = connect_to(port);
    if (fd >= 0) {
      ::close(fd);
      return;
    }
    std::this_thread::sleep_for(std::chrono::milliseconds(20));
  }
  FAIL() << "nothing listens on port " << port;
}

int start_nginx(const std::filesystem::path& root, const std::filesystem::path& prefix, int port) {
  std::filesystem::create_directories(prefix / "logs");
  std::ofstream(prefix / "nginx.conf")
      << "daemon off; master_process off; worker_processes 1;\n"
      << "pid " << (prefix / "nginx.pid").string() << ";\n"
      << "error_log " << (prefix / "logs/error.log").string() << ";\n"
      << "events { worker_connections 64; }\n"
      << "http { access_log off; client_body_temp_path " << prefix.string() << "/body;\n"
      << "  proxy_temp_path " << prefix.string() << "/proxy; fastcgi_temp_path " << prefix.string()
      << "/fastcgi;\n  uwsgi_temp_path " << prefix.string() << "/uwsgi; scgi_temp_path "
      << prefix.string() << "/scgi;\n"
      << "  types { application/json json; } default_type application/octet-stream;\n"
      << "  server { listen 127.0.0.1:" << port << "; root " << root.string() << "; } }\n";
  const pid_t nginx = ::fork();
  if (nginx == 0) {
    if (!std::freopen("/dev/null", "w", stderr)) ::_exit(127);
    ::execlp("nginx", "nginx", "-p", prefix.c_str(), "-c", (prefix / "nginx.conf").c_str(),
             nullptr);
    ::_exit(127);
  }
  wait_for(port);
  return nginx;
}

}  // namespace relief::testing
