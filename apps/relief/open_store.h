#pragma once
#include <string>

#include "relief/base/result.h"
#include "relief/tiles/store.h"

namespace relief::cli {

// A store directory, or a store served over HTTP: "http://host:port/path/",
// several comma-separated URLs for mirrors. A remote store goes through a
// disk cache under `cache_dir` (within `cache_bytes`) when one is given.
Result<tiles::Store> open_store(const std::string& location, const std::string& cache_dir = "",
                                uint64_t cache_bytes = uint64_t{1} << 30);

}  // namespace relief::cli
