#pragma once
// The geometric error of every tile of an elevation store: the largest
// vertical distance between the tile's level's full mesh (full_mesh.h) and the
// finest samples below it, nodata and the data's edge left out (the definition
// is in docs/store-format.md, "Geometric error"). Computed exactly and out of
// core: one pass over the finest tiles in Morton order, each compared with
// every ancestor, the ancestors' decoded tiles in a small LRU.
#include <filesystem>
#include <functional>
#include <memory>
#include <span>

#include "relief/base/parallel.h"
#include "relief/base/progress.h"
#include "relief/base/result.h"
#include "relief/tiles/level_index.h"
#include "relief/tiles/tile_file.h"

namespace relief::tiles {

class Store;

// A bordered Float32 tile with nodata kept as NaN. Called concurrently.
using BorderedTileReader =
    std::function<Result<std::shared_ptr<const Raster>>(const geo::TileKey&)>;

// Sets the error of every entry of `indices`: consecutive levels, coarsest
// first, the finest last (its errors are 0). `shape` is the store's tiles'.
// `read_interior`, if given, reads a finest tile's interior alone (no
// border; only the interior is compared), where that is cheaper than `read`.
Status compute_geometric_errors(std::span<LevelIndex> indices, const TileShape& shape,
                                const BorderedTileReader& read, Executor& executor,
                                Progress& progress, const BorderedTileReader& read_interior = {});

// What compute_geometric_errors keeps of ancestors' tiles in memory, for a
// caller that budgets it: a few tiles per level and worker.
uint64_t ancestor_cache_bytes(const TileShape& shape, size_t levels, unsigned workers);

// The tiles of an open store, and those of a store being written under `root`
// (no manifest needed).
BorderedTileReader store_tile_reader(const Store& store);
BorderedTileReader directory_tile_reader(const std::filesystem::path& root, const TileShape& shape);

// Rounds a non-negative distance up to the nearest float (never below it).
float round_up_to_float(double distance);

}  // namespace relief::tiles
