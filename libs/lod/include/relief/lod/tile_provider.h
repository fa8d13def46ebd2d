#pragma once
// Where a TerrainModel gets decoded elevation tiles (heights, nodata as 0),
// and the renderer imagery tiles.
//
// Complete frames use a provider that waits for every tile. Interactive
// frames use one that never waits (libs/stream): a tile that is not resident
// is requested with the view priority of the quad that wants it, and the
// selection keeps drawing that quad's resident ancestor meanwhile.
#include <functional>
#include <memory>

#include "relief/base/result.h"
#include "relief/geo/tile_key.h"
#include "relief/tiles/raster.h"

namespace relief::tiles {
class Store;
}

namespace relief::lod {

using TilePtr = std::shared_ptr<const tiles::Raster>;

class TileProvider {
 public:
  virtual ~TileProvider() = default;
  // Whether get() loads a tile that is not resident (and waits for it).
  virtual bool blocking() const = 0;
  // The tile, or (non-blocking providers) nullptr when it is not resident yet.
  // The key is a tile of the store. The returned pointer pins the tile: it
  // stays resident while the caller holds it.
  virtual Result<TilePtr> get(const geo::TileKey& key) = 0;
  // The view wants this non-resident tile; higher priorities load first. A
  // frame's requests replace the previous frame's (stale ones are cancelled).
  virtual void request(const geo::TileKey& /*key*/, double /*priority*/) {}
  // The bracket of one frame's requests.
  virtual void begin_frame() {}
  virtual void end_frame() {}
  // Work to do on each freshly decoded tile, on the thread that decoded it,
  // before the tile becomes resident (non-blocking providers; others never
  // call it). An empty function removes it.
  using Prepare = std::function<void(const geo::TileKey&, const tiles::Raster&)>;
  virtual void set_prepare(Prepare /*prepare*/) {}
  // Whoever prepared this tile dropped what it made of it (a cache budget):
  // evict the tile unless a caller holds it, so that when a view wants it
  // again it loads, and is prepared, again, off the caller's thread.
  // Thread-safe; non-blocking providers (others ignore it).
  virtual void forget(const geo::TileKey& /*key*/) {}
};

// Reads each tile from the store when asked, keeping decoded tiles within a
// byte budget (least recently used first out).
std::unique_ptr<TileProvider> blocking_provider(const tiles::Store& store, uint64_t cache_bytes);

// A store tile as heights: Float32 samples with NaN (nodata) replaced by 0;
// an error naming the store for anything else.
Result<TilePtr> decode_heights(const tiles::Store& store, const geo::TileKey& key);
// A store tile ready to draw: heights as above, imagery (RGBA8) with its
// colours premultiplied by alpha.
Result<TilePtr> decode_tile(const tiles::Store& store, const geo::TileKey& key);

}  // namespace relief::lod
