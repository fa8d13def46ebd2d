#pragma once
// The web side of `relief serve` (docs/web.md): answers for the routes web
// clients read, tiles made on request and kept, encoded, in a byte-budgeted
// cache; concurrent requests for one tile make it once; and the pages that
// show them, as plain files of a web root.
//   /terrain/layer.json, /terrain/{z}/{x}/{y}.terrain   Cesium quantized-mesh
//   /terrain-rgb/{z}/{x}/{y}.png, /terrarium/...        MapLibre raster-dem
//   /imagery/{z}/{x}/{y}.png                            imagery, Web Mercator
//   /imagery/webp/{z}/{x}/{y}.webp                      the same, lossy WebP
//   /imagery-geo/{z}/{x}/{y}.png                        imagery, Cesium's geographic tiling
//   (each with tiles.json or layer.json beside)
//   /view/, /map/, /lib/cesium/..., /lib/maplibre/...  pages and libraries
#include <cstdint>
#include <memory>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include "relief/web/geographic_tiles.h"
#include "relief/web/raster_tiles.h"
#include "relief/web/static_files.h"
#include "relief/web/terrain_tiler.h"
#include "relief/web/web_answer.h"

namespace relief::web {

struct WebServiceOptions {
  std::string name = "relief";                // the tileset's name in layer.json
  uint64_t cache_bytes = uint64_t{64} << 20;  // encoded tiles kept
  std::vector<StaticMount> pages;             // web_root_mounts(root); empty: no pages
};

// What is served; any may be null (its routes then answer 404).
struct WebLayers {
  std::shared_ptr<const TerrainTiler> terrain;                // /terrain/
  std::shared_ptr<const RasterTiler> dem;                     // /terrain-rgb/, /terrarium/
  std::shared_ptr<const RasterTiler> imagery;                 // /imagery/
  std::shared_ptr<const GeographicTiles> imagery_geographic;  // /imagery-geo/
};

class WebService {
 public:
  WebService(WebLayers layers, WebServiceOptions options = {});
  // Terrain alone; null: no tile routes.
  WebService(std::shared_ptr<const TerrainTiler> terrain, WebServiceOptions options = {});
  ~WebService();
  // The answer for a request target, nullopt when it names nothing here (or
  // a tile that is not available): the server's 404. Thread-safe.
  std::optional<WebAnswer> answer(std::string_view target) const;
  // The same when it needs no making (a tile in the cache, a tileset's
  // description), else nullopt: quick, for the server's event loops, which
  // leave the rest to answer() on their generation threads. Thread-safe.
  std::optional<WebAnswer> answer_if_made(std::string_view target) const;

  uint64_t tiles_made() const;  // tiles generated (not answered from the cache)

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace relief::web
