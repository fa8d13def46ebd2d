#pragma once
// Store files over HTTP(S) through libcurl: connections reused (a pool of
// handles), timeouts, retries with exponential backoff on connection errors,
// 5xx answers, truncated bodies and checksum failures; every file is verified
// (StoreSource::verify) before it is returned, so bad data is never used or
// cached. Several servers at once: as mirrors (each request tries the servers
// in turn, starting with a different one per file, and fails over), or with
// tiles distributed over them by the cyclic order of their Morton index
// (Comet's distributed memory, seed 000 §3.1), where manifest and indices may
// come from any server.
#include <memory>
#include <string>
#include <vector>

#include "relief/tiles/store_source.h"

namespace relief::net {

enum class ServerLayout {
  Mirrors,      // every server holds the whole store
  Distributed,  // tile i (Morton order) lives on server i mod n
};

struct HttpOptions {
  std::vector<std::string> base_urls;  // "http://host:port/path/", one or more
  ServerLayout layout = ServerLayout::Mirrors;
  long connect_timeout_ms = 2000;
  long timeout_ms = 10000;
  int attempts = 4;      // per server, before failing over or giving up
  long backoff_ms = 25;  // doubled after each failed attempt
};

struct HttpStats {
  uint64_t requests = 0, retries = 0, failovers = 0, bytes = 0, rejected = 0;
};

class HttpSource : public tiles::StoreSource {
 public:
  static Result<std::shared_ptr<HttpSource>> create(HttpOptions options);
  virtual HttpStats stats() const = 0;
};

// "http://a/,http://b/" as mirrors; "cyclic:http://a/,http://b/" as the
// servers of a store spread cyclically (`relief serve --share i/n`, or
// `relief split` directories behind any static server), in share order; a
// local path otherwise.
Result<std::shared_ptr<const tiles::StoreSource>> source_for(const std::string& location);

}  // namespace relief::net
