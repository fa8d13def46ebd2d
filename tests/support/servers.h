#pragma once
// Real servers on loopback for the tests: ports, waiting for a listener, and
// an nginx serving a directory.
#include <filesystem>
#include <string>

namespace relief::testing {

// A loopback port nothing listens on right now.
int free_port();
// For fake servers: reads a request head from `fd` and returns its target
// without the leading '/' ("" when the head is cut short).
std::string read_request_path(int fd);
// A connected socket to 127.0.0.1:port, or -1.
int connect_to(int port);
// Waits (up to 4 s) until something accepts connections on the port; a test
// failure otherwise.
void wait_for(int port);
// Starts nginx in the foreground serving `root` on the port, its files under
// `prefix`; returns its pid once it listens (stop it with SIGTERM).
int start_nginx(const std::filesystem::path& root, const std::filesystem::path& prefix, int port);

}  // namespace relief::testing
