#pragma once
// `relief serve`: a read-only HTTP/1.1 server for one store directory. Only
// the store's own files are served (manifest.json, level indices, tiles, by
// their canonical paths), so no request can reach anything else; GET and HEAD
// with keep-alive, Content-Length, ETag (If-None-Match gives 304) and cache
// headers; a pool of worker threads serves many clients at once.
#include <cstdint>
#include <filesystem>
#include <memory>
#include <optional>
#include <string>

#include "relief/base/result.h"

namespace relief::serve {

struct ServeOptions {
  std::filesystem::path root;
  std::string bind = "127.0.0.1";
  int port = 8080;  // 0: any free port (see StoreServer::port)
  int threads = 16;
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

}  // namespace relief::serve
