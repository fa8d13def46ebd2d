#include "http_client.h"

#include <sys/socket.h>
#include <sys/time.h>
#include <unistd.h>

#include <cctype>
#include <sstream>

#include "servers.h"

namespace relief::testing {

int connect_client(int port) {
  const int fd = connect_to(port);
  if (fd < 0) return -1;
  timeval timeout{5, 0};
  ::setsockopt(fd, SOL_SOCKET, SO_RCVTIMEO, &timeout, sizeof timeout);
  return fd;
}

Response read_response(int fd, bool head_request) {
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

Response request(int port, const std::string& raw, bool head_request) {
  const int fd = connect_client(port);
  if (fd < 0) return {};
  ::send(fd, raw.data(), raw.size(), MSG_NOSIGNAL);
  Response r = read_response(fd, head_request);
  ::close(fd);
  return r;
}

Response get(int port, const std::string& path) {
  return request(port, "GET " + path + " HTTP/1.1\r\nHost: x\r\nConnection: close\r\n\r\n");
}

bool closed_by_server(int fd) {
  char buf[65536];
  for (;;) {
    const ssize_t n = ::recv(fd, buf, sizeof buf, 0);
    if (n == 0) return true;
    if (n < 0) return errno == ECONNRESET;  // a timeout: still open
  }
}

}  // namespace relief::testing
