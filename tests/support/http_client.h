#pragma once
// A minimal HTTP/1.1 client for the server tests: raw request bytes out, one
// parsed response in. Every socket it opens gives up after a generous receive
// timeout, so a server that hangs fails a test instead of hanging it.
#include <map>
#include <string>

namespace relief::testing {

struct Response {
  int status = 0;                              // 0: no (complete) response head
  std::map<std::string, std::string> headers;  // lower-case names
  std::string body;
};

// A connected loopback socket whose receives time out after 5 s, or -1.
int connect_client(int port);
// Reads one response from a connection (Content-Length framed, or to EOF).
Response read_response(int fd, bool head_request = false);
// Sends `raw` on a new connection, reads one response, closes.
Response request(int port, const std::string& raw, bool head_request = false);
// GET with `Connection: close`.
Response get(int port, const std::string& path);
// Whether the server closed the connection: reading on (and discarding what
// arrives) meets end of file or a reset before a receive times out.
bool closed_by_server(int fd);

}  // namespace relief::testing
