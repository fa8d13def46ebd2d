#pragma once
// The web side of `relief serve` (docs/web.md): answers for the routes web
// clients read, tiles made on request and kept, encoded, in a byte-budgeted
// cache; concurrent requests for one tile make it once.
//   /terrain/layer.json, /terrain/{z}/{x}/{y}.terrain   Cesium quantized-mesh
#include <cstdint>
#include <memory>
#include <optional>
#include <string>
#include <string_view>

#include "relief/web/terrain_tiler.h"

namespace relief::web {

struct WebAnswer {
  std::string content_type;
  std::string content_encoding;  // "gzip" for .terrain bodies
  std::string body;
};

struct WebServiceOptions {
  std::string name = "relief";                // the tileset's name in layer.json
  uint64_t cache_bytes = uint64_t{64} << 20;  // encoded tiles kept
};

class WebService {
 public:
  WebService(std::shared_ptr<const TerrainTiler> terrain, WebServiceOptions options = {});
  ~WebService();
  // The answer for a request target, nullopt when it names nothing here (or
  // a tile that is not available): the server's 404. Thread-safe.
  std::optional<WebAnswer> answer(std::string_view target) const;

  uint64_t tiles_made() const;  // tiles generated (not answered from the cache)

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace relief::web
