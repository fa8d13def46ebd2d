#pragma once
#include <string>

#include "relief/base/result.h"
#include "relief/stream/throttled_source.h"
#include "relief/tiles/store.h"

namespace relief::cli {

struct StoreAccess {
  std::string cache_dir;  // remote stores: a disk cache here, when not empty
  uint64_t cache_bytes = uint64_t{1} << 30;
  stream::LinkModel link;  // simulated network in front of the store (none by default)
};

// A store directory, or a store served over HTTP: "http://host:port/path/",
// several comma-separated URLs for mirrors.
Result<tiles::Store> open_store(const std::string& location, const StoreAccess& access = {});

}  // namespace relief::cli
