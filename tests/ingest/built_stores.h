#pragma once
// Stores built once per test binary from the bundled data and shared by tests.
#include <string>
#include <vector>

#include "relief/ingest/build.h"
#include "relief/tiles/store.h"

namespace relief::testing {

// Builds (on first use) a store named `name` from `options` (output is filled in).
const tiles::Store& built_store(const std::string& name, ingest::BuildOptions options);

// One bundled SRTM tile (data/srtm/TILE.hgt.zip) as an elevation store.
const tiles::Store& srtm_store(const std::string& tile);

// The N41E001 + N42E001 pair (Catalonia + Pyrenees), lossless.
const tiles::Store& pyrenees_store();
std::vector<std::string> pyrenees_inputs();

// Reads tile `key` or fails the current test.
tiles::Tile must_read(const tiles::Store& store, const geo::TileKey& key);

}  // namespace relief::testing
