#pragma once
// The local disk cache of a remote store (cache level L1, seed 003 Fig. 1.8):
// files fetched from the upstream source are kept under a directory within a
// byte budget, least recently used first out. Only verified files are
// written (atomically), and every cached file is verified again when read,
// so a damaged cache heals by fetching anew. Concurrent requests for one file
// share one upstream fetch. Files are keyed by the store's identity (its
// location and a hash of its manifest, fetched anew on every create), so
// several stores share one directory and a changed store is never served stale.
#include <filesystem>
#include <memory>

#include "relief/tiles/store_source.h"

namespace relief::net {

struct DiskCacheStats {
  uint64_t hits = 0, misses = 0, evictions = 0, shared = 0, repaired = 0;
  uint64_t bytes = 0;  // on disk now
};

class DiskCache : public tiles::StoreSource {
 public:
  // Files already under `directory` (from an earlier run) count from the
  // start. Fetches the manifest from the upstream; without an answer, the
  // last one cached for that location (offline), else the upstream's error.
  static Result<std::shared_ptr<DiskCache>> create(
      std::shared_ptr<const tiles::StoreSource> upstream, const std::filesystem::path& directory,
      uint64_t budget_bytes);
  virtual DiskCacheStats stats() const = 0;
  // Where this store's files are kept (under the cache directory).
  virtual std::filesystem::path store_directory() const = 0;
};

}  // namespace relief::net
