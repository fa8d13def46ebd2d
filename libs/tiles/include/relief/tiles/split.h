#pragma once
// `relief split`: a store spread cyclically over N servers (seed 000 §3.1).
// Share i holds the manifest, every level index and the tiles whose Morton
// index modulo N is i, so no server is a hot spot for any view; any static
// server (nginx, ...) can serve the share directories, and readers take them
// with a `cyclic:` URL list in share order. `relief serve --share i/N` serves
// the same share from the whole store without copying.
#include <filesystem>

#include "relief/base/result.h"

namespace relief::tiles {

struct SplitReport {
  uint64_t tiles = 0;
  uint64_t linked = 0;  // hard links (the rest were copied: another file system)
};

// Writes `output`/share-0 ... share-(N-1). `output` must not exist; it is
// written beside itself under a temporary name and renamed when complete.
Result<SplitReport> split_store(const std::filesystem::path& store,
                                const std::filesystem::path& output, uint32_t shares);

std::filesystem::path share_directory(const std::filesystem::path& output, uint32_t index);

}  // namespace relief::tiles
