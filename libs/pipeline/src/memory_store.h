#pragma once
// A store presented from memory (fused and processed elevation layers): the
// manifest and level indexes are made when it is opened, each tile is made
// when it is fetched (on the fetching thread: the loader's when drawing).
#include <cstddef>
#include <functional>
#include <string>
#include <vector>

#include "relief/base/result.h"
#include "relief/geo/tile_key.h"
#include "relief/tiles/level_index.h"
#include "relief/tiles/manifest.h"
#include "relief/tiles/store.h"
#include "relief/tiles/store_source.h"

namespace relief::pipeline {

// Encodes tile `key`'s file; called concurrently from any thread.
using TileEncoder = std::function<Result<std::vector<std::byte>>(const geo::TileKey& key)>;

// Opens the store `manifest` and `indices` describe, named `name` in
// messages, whose tiles `encode` makes.
Result<tiles::Store> open_memory_store(std::string name, const tiles::Manifest& manifest,
                                       const std::vector<tiles::LevelIndex>& indices,
                                       TileEncoder encode);

}  // namespace relief::pipeline
