#pragma once
#include <string>

#include "relief/base/result.h"
#include "relief/net/disk_cache.h"
#include "relief/stream/throttled_source.h"
#include "relief/tiles/store.h"

namespace relief::cli {

struct StoreAccess {
  std::string cache_dir;  // remote stores: a disk cache here, when not empty
  uint64_t cache_bytes = uint64_t{1} << 30;
  stream::LinkModel link;  // simulated network in front of the store (none by default)
};

// A store directory, or a store served over HTTP: "http://host:port/path/",
// several comma-separated URLs for mirrors. `disk_cache`, when given, receives
// the disk cache in front of a remote store (for its statistics).
Result<tiles::Store> open_store(const std::string& location, const StoreAccess& access = {},
                                std::shared_ptr<net::DiskCache>* disk_cache = nullptr);

}  // namespace relief::cli
