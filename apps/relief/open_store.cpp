#include "open_store.h"

#include "relief/net/http_source.h"

namespace relief::cli {

Result<tiles::Store> open_store(const std::string& location, const StoreAccess& access,
                                std::shared_ptr<net::DiskCache>* disk_cache) {
  const bool remote = location.starts_with("http://") || location.starts_with("https://") ||
                      location.starts_with("cyclic:");
  const bool simulated = access.link.latency.count() > 0 || access.link.bits_per_second > 0;
  std::shared_ptr<const tiles::StoreSource> source;
  if (remote) {
    source = RELIEF_TRY(net::source_for(location));
  } else {
    // Checks the directory with clear errors first.
    tiles::Store local = RELIEF_TRY(tiles::Store::open(location));
    if (!simulated) return local;
    source = tiles::local_source(location);
  }
  if (simulated) source = stream::throttled_source(std::move(source), access.link);
  if (remote && !access.cache_dir.empty()) {
    auto cache =
        RELIEF_TRY(net::DiskCache::create(std::move(source), access.cache_dir, access.cache_bytes));
    if (disk_cache) *disk_cache = cache;
    source = std::move(cache);
  }
  return tiles::Store::open(std::move(source));
}

}  // namespace relief::cli
