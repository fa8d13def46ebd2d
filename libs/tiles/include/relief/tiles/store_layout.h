#pragma once
// Where things live inside a store directory (seed 003 §1.2.4):
//   manifest.json                 global description of the dataset
//   <level>/index.rli             per-level metadata index (presence + min/max)
//   <level>/[bN/.../b1/]b0.rtile  one file per non-empty tile
// The tile's Morton index (2*level bits) is cut into 12-bit blocks, most
// significant first, each written as three hex digits; all but the last block
// name directories, so no directory holds more than 4096 entries.
#include <filesystem>
#include <optional>
#include <string>

#include "relief/geo/tile_key.h"

namespace relief::tiles {

inline constexpr const char* kManifestName = "manifest.json";
inline constexpr const char* kLevelIndexName = "index.rli";
inline constexpr const char* kTileExtension = ".rtile";

// Path of a tile relative to the store root, with '/' separators (also its URL path).
std::string tile_relative_path(const geo::TileKey& key);
std::string level_index_relative_path(int level);
// Inverse of tile_relative_path; nullopt for anything that is not a tile path.
std::optional<geo::TileKey> tile_key_from_relative_path(const std::string& path);

}  // namespace relief::tiles
