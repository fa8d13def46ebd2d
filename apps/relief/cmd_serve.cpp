#include <csignal>
#include <cstdio>

#include <fmt/format.h>

#include "args.h"
#include "commands.h"
#include "relief/serve/store_server.h"

namespace relief::cli {

namespace {
constexpr const char* kHelp =
    R"(usage: relief serve STORE [--port P] [--bind ADDR] [--threads N]

Serves a store read-only over HTTP/1.1 until interrupted: only the store's own
files (manifest.json, level indices, tiles) by their canonical paths, GET and
HEAD, keep-alive, Content-Length, ETag with If-None-Match, cache headers.
Any static web server (nginx, ...) serving the store directory works the same.

options:
  --port P       TCP port (default 8080; 0: any free port, printed)
  --bind ADDR    IPv4 address to listen on (default 127.0.0.1)
  --threads N    connections served at once (default 16)
)";
}  // namespace

int run_serve(const std::vector<std::string>& argv) {
  if (wants_help(argv)) return print_help(kHelp);
  auto args = Args::parse(argv, {{"--port"}, {"--bind"}, {"--threads"}}, "serve");
  if (!args) return report_error(args.error().message);
  if (args->positional().size() != 1) return report_error("serve: expected exactly one STORE");
  serve::ServeOptions o;
  o.root = args->positional()[0];
  auto port = args->get_int("--port", 0, 65535);
  if (!port) return report_error(port.error().message);
  o.port = port->value_or(8080);
  if (auto b = args->get("--bind")) o.bind = *b;
  auto threads = args->get_int("--threads", 1, 1024);
  if (!threads) return report_error(threads.error().message);
  o.threads = threads->value_or(16);
  // Block the stop signals before the server's threads start, so only the
  // main thread receives them (sigwait below).
  sigset_t stop_signals;
  sigemptyset(&stop_signals);
  sigaddset(&stop_signals, SIGINT);
  sigaddset(&stop_signals, SIGTERM);
  pthread_sigmask(SIG_BLOCK, &stop_signals, nullptr);
  auto server = serve::StoreServer::start(o);
  if (!server) return report_error(server.error().message);
  std::printf("serving %s on http://%s:%d/\n", o.root.c_str(), o.bind.c_str(), (*server)->port());
  std::fflush(stdout);
  int signal = 0;
  sigwait(&stop_signals, &signal);
  (*server)->stop();
  return 0;
}

}  // namespace relief::cli
