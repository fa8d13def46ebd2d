#include "open_store.h"

#include "relief/net/disk_cache.h"
#include "relief/net/http_source.h"

namespace relief::cli {

Result<tiles::Store> open_store(const std::string& location, const std::string& cache_dir,
                                uint64_t cache_bytes) {
  if (!location.starts_with("http://") && !location.starts_with("https://")) {
    return tiles::Store::open(location);
  }
  auto source = RELIEF_TRY(net::source_for(location));
  if (!cache_dir.empty()) {
    auto cache = RELIEF_TRY(net::DiskCache::create(std::move(source), cache_dir, cache_bytes));
    source = std::move(cache);
  }
  return tiles::Store::open(std::move(source));
}

}  // namespace relief::cli
