#pragma once
// `relief upgrade`: brings a local store of an older format up to the current
// one. From format 1: computes every tile's geometric error (elevation; 0 for
// imagery and SAR) and rewrites the level indexes (version 2) and the manifest.
#include <filesystem>

#include "relief/base/parallel.h"
#include "relief/base/progress.h"
#include "relief/base/result.h"

namespace relief::tiles {

struct UpgradeReport {
  int from_version = 0;  // the store's format before; == to_version: nothing done
  int to_version = 0;
  uint64_t tiles = 0;
};

// Nothing is written until every error is computed; the indexes are then
// replaced one by one (atomically each) and the manifest last, so an
// interrupted upgrade leaves a store that still reads as format 1 and that
// the same command finishes.
Result<UpgradeReport> upgrade_store(const std::filesystem::path& root, Executor& executor,
                                    Progress& progress);

}  // namespace relief::tiles
