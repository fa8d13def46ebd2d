#include "availability.h"

#include <algorithm>
#include <map>
#include <nlohmann/json.hpp>

#include "relief/tiles/store.h"

namespace relief::web {
namespace {

// Availability as rectangles: runs of columns per row, a run continued
// while the rows above repeat it. `keys` sorted by (y, x).
nlohmann::json ranges_of(const std::vector<TerrainKey>& keys) {
  struct Range {
    uint32_t start_x, end_x, start_y, end_y;
  };
  std::vector<Range> done;
  std::map<std::pair<uint32_t, uint32_t>, Range> open;  // by (start_x, end_x)
  size_t i = 0;
  while (i < keys.size()) {
    const uint32_t y = keys[i].y;
    std::map<std::pair<uint32_t, uint32_t>, Range> next;
    while (i < keys.size() && keys[i].y == y) {
      const uint32_t start = keys[i].x;
      uint32_t end = start;
      while (i + 1 < keys.size() && keys[i + 1].y == y && keys[i + 1].x == end + 1) ++i, ++end;
      ++i;
      auto it = open.find({start, end});
      if (it != open.end() && it->second.end_y + 1 == y) {
        Range r = it->second;
        r.end_y = y;
        next[{start, end}] = r;
        open.erase(it);
      } else {
        next[{start, end}] = Range{start, end, y, y};
      }
    }
    for (auto& [_, r] : open) done.push_back(r);
    open = std::move(next);
  }
  for (auto& [_, r] : open) done.push_back(r);
  nlohmann::json out = nlohmann::json::array();
  for (const Range& r : done) {
    out.push_back(
        {{"startX", r.start_x}, {"startY", r.start_y}, {"endX", r.end_x}, {"endY", r.end_y}});
  }
  return out;
}

}  // namespace

bool meets(const TerrainKey& key, const std::optional<geo::GeoBox>& bbox) {
  return !bbox || key.bounds().intersects(*bbox);
}

std::vector<TerrainKey> available_tiles(const tiles::Store& store, int level, int max_level,
                                        const std::optional<geo::GeoBox>& bbox) {
  std::vector<TerrainKey> keys;
  if (level == 0) return {{0, 0, 0}, {0, 1, 0}};
  if (level < 0 || level > max_level) return keys;
  for (const tiles::IndexEntry& e : store.index(level).entries()) {
    const uint32_t y = (1u << level) - 1 - e.key.y;
    for (const uint32_t x : {2 * e.key.x, 2 * e.key.x + 1}) {
      const TerrainKey key{level, x, y};
      if (meets(key, bbox)) keys.push_back(key);
    }
  }
  std::sort(keys.begin(), keys.end(), [](const TerrainKey& a, const TerrainKey& b) {
    return std::tie(a.y, a.x) < std::tie(b.y, b.x);
  });
  return keys;
}

std::string layer_json(const tiles::Store& store, const std::string& name, int max_level,
                       const std::optional<geo::GeoBox>& bbox, bool normals) {
  const geo::GeoBox& e = store.manifest().extent;
  // Every level, for clients that read layer.json only; CesiumJS reads the
  // levels below 10 from the tiles' metadata instead.
  nlohmann::json available = nlohmann::json::array();
  for (int level = 0; level <= max_level; ++level) {
    available.push_back(ranges_of(available_tiles(store, level, max_level, bbox)));
  }
  nlohmann::json extensions = {"metadata"};
  if (normals) extensions.insert(extensions.begin(), "octvertexnormals");
  const nlohmann::json layer = {
      {"tilejson", "2.1.0"},
      {"name", name},
      {"description", "relief terrain: quantized-mesh tiles of an elevation store"},
      {"version", "1.0.0"},
      {"format", "quantized-mesh-1.0"},
      {"scheme", "tms"},
      {"projection", "EPSG:4326"},
      {"tiles", {"{z}/{x}/{y}.terrain"}},
      {"bounds",
       {std::max(e.west, -180.0), std::max(e.south, -90.0), std::min(e.east, 180.0),
        std::min(e.north, 90.0)}},
      {"minzoom", 0},
      {"maxzoom", max_level},
      {"attribution", ""},
      {"extensions", extensions},
      // CesiumJS needs the two together: "metadata" alone leaves its
      // availability tiles undefined and every tile with the extension fails.
      {"metadataAvailability", kMetadataLevels},
      {"available", available},
  };
  return layer.dump();
}

std::string metadata_json(const tiles::Store& store, const TerrainKey& key, int max_level,
                          const std::optional<geo::GeoBox>& bbox) {
  nlohmann::json available = nlohmann::json::array();
  for (int level = key.level + 1; level <= std::min(key.level + kMetadataLevels, max_level);
       ++level) {
    const int shift = level - key.level;
    std::vector<TerrainKey> below;
    for (const TerrainKey& k : available_tiles(store, level, max_level, bbox)) {
      if ((k.x >> shift) == key.x && (k.y >> shift) == key.y) below.push_back(k);
    }
    available.push_back(ranges_of(below));
  }
  return nlohmann::json{{"available", available}}.dump();
}

}  // namespace relief::web
