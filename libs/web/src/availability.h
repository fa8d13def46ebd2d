#pragma once
// Which Cesium terrain tiles a store has, in the forms clients read: the
// `available` rectangles of layer.json and of the `metadata` extension.
#include <optional>
#include <string>
#include <vector>

#include "relief/web/terrain_tiler.h"

namespace relief::tiles {
class Store;
}

namespace relief::web {

// Levels a tile's metadata covers below it (layer.json's metadataAvailability).
inline constexpr int kMetadataLevels = 10;

bool meets(const TerrainKey& key, const std::optional<geo::GeoBox>& bbox);

// Every available tile of a level, sorted by (y, x).
std::vector<TerrainKey> available_tiles(const tiles::Store& store, int level, int max_level,
                                        const std::optional<geo::GeoBox>& bbox);

std::string layer_json(const tiles::Store& store, const std::string& name, int max_level,
                       const std::optional<geo::GeoBox>& bbox, bool normals);

// The `metadata` extension's JSON of `key`: the available tiles below it,
// level by level, for the next kMetadataLevels levels.
std::string metadata_json(const tiles::Store& store, const TerrainKey& key, int max_level,
                          const std::optional<geo::GeoBox>& bbox);

}  // namespace relief::web
