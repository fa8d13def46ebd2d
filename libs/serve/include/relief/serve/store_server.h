#pragma once
// `relief serve`: a read-only HTTP/1.1 server for one store directory. Only
// the store's own files are served (manifest.json, level indices, tiles, by
// their canonical paths), so no request can reach anything else; GET and HEAD
// with keep-alive, Content-Length, ETag (If-None-Match gives 304), single byte
// ranges and cache headers. Event loops (epoll) serve every connection without
// blocking on any one client; deadlines and a connection limit keep slow, idle
// or hostile clients from starving the others.
#include <chrono>
#include <cstdint>
#include <filesystem>
#include <functional>
#include <memory>
#include <optional>
#include <string>
#include <string_view>

#include "relief/base/result.h"

namespace relief::serve {

// An answer made on request rather than read from a store file: web tiles and
// pages (libs/web, plugged in by apps/relief; serve does not depend on it).
struct GeneratedAnswer {
  std::string content_type;
  std::string content_encoding;  // "" or, for a body stored compressed, "gzip"
  std::string body;
};
// Called for every GET or HEAD whose path is not one of the store's files,
// on the server's generation threads (ServeOptions::generate_threads),
// several at once: it must be thread-safe. The event loops go on serving
// their other connections meanwhile; the connection that asked gets its
// answer when it is made (in order with its other requests). nullopt: 404.
using Generator = std::function<std::optional<GeneratedAnswer>(std::string_view target)>;

struct ServeOptions {
  std::filesystem::path root;
  std::string bind = "127.0.0.1";
  int port = 8080;   // 0: any free port (see StoreServer::port)
  int threads = 16;  // event-loop threads; each serves any number of connections
  // Connections open at once; further ones get 503 and are closed at once.
  int max_connections = 1024;
  // A request head must arrive whole within this time of the connection
  // opening or the previous answer ending (so idle keep-alive connections and
  // clients sending a byte at a time are closed after it).
  std::chrono::milliseconds read_timeout{10'000};
  // An answer that makes no progress for this long (a client that does not
  // read) is dropped.
  std::chrono::milliseconds write_timeout{10'000};
  // Serve one share of a store spread cyclically over `share_count` servers
  // (seed 000 §3.1): tiles whose Morton index modulo share_count is
  // share_index; the manifest and level indices always. Other tiles get 404.
  // Readers take such servers with the `cyclic:` URL list (net::source_for).
  uint32_t share_index = 0, share_count = 1;
  // Answers for paths outside the store's files (empty: 404 for all).
  Generator generate;
  // Threads that run `generate` (0: one per core).
  int generate_threads = 0;
  // Optional, quick and thread-safe: an answer `generate` has made already
  // (a cached tile), given on the event loop without a trip to the pool;
  // nullopt: ask `generate`.
  Generator generate_at_once;
  // The clock deadlines are measured with (tests move it forward); empty:
  // std::chrono::steady_clock::now.
  std::function<std::chrono::steady_clock::time_point()> clock;
};

class StoreServer {
 public:
  // Checks the store, binds and starts serving; fails naming the problem.
  static Result<std::unique_ptr<StoreServer>> start(const ServeOptions& options);
  virtual ~StoreServer() = default;
  virtual int port() const = 0;
  // Stops accepting, closes connections, joins the threads.
  virtual void stop() = 0;
};

// The file a request path names inside a store, or nullopt when the path is
// not one of the store's files (anything else, any traversal, any encoding).
std::optional<std::string> store_file_for(const std::string& request_path);

// Whether the store file `file` (a relative path) belongs to share `index` of
// `count`: tiles by Morton index modulo count, every other file to each share.
bool in_share(const std::string& file, uint32_t index, uint32_t count);

}  // namespace relief::serve
