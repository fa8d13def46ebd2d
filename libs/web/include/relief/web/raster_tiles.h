#pragma once
// Web Mercator XYZ PNG tiles of a store (docs/web.md): heights encoded as
// Terrain-RGB or Terrarium for MapLibre `raster-dem` sources, or the
// colours of an imagery store for `raster` sources.
//
// Pixel (i, j) of tile (z, x, y) is the store's value at the pixel's centre
// (web_mercator.h): bilinear over the cell-centred samples of the level
// that the pixel's row reads (source_level), with samples read from their
// owning tiles across tile boundaries. Beyond the store's finest level,
// tiles are upsampled from it.
#include <cstddef>
#include <cstdint>
#include <memory>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include "relief/base/result.h"
#include "relief/tiles/raster.h"
#include "relief/web/dem_encoding.h"
#include "relief/web/web_mercator.h"

namespace relief::tiles {
class Store;
}

namespace relief::web {

struct RasterTileOptions {
  int tile_size = 256;  // pixels a side: 256 or 512
  // The finest zoom available; -1: natural_max_zoom(). Larger zooms are
  // upsampled from the store's finest level.
  int max_zoom = -1;
  // Only tiles meeting this box (and the store's extent) are available.
  std::optional<geo::GeoBox> bbox;
  uint64_t cache_bytes = uint64_t{64} << 20;  // decoded store tiles kept
};

// Built once per store and tile size; every method is thread-safe.
class RasterTiler {
 public:
  // An elevation store (Float32, 1 band) or an imagery store (UInt8 RGBA).
  static Result<RasterTiler> create(std::shared_ptr<const tiles::Store> store,
                                    RasterTileOptions options = {});
  ~RasterTiler();
  RasterTiler(RasterTiler&&) noexcept;
  RasterTiler& operator=(RasterTiler&&) noexcept;

  bool holds_elevation() const;  // false: imagery
  int tile_size() const;
  int max_zoom() const;
  // The first zoom at which every pixel of the store's extent reads its
  // finest level; a client upsamples beyond it as well as relief would.
  int natural_max_zoom() const;
  // The store level a row of pixels at latitude `lat` of zoom z reads: the
  // one whose sample spacing is within [1, 2) of the pixel's north-south
  // size, L = z + log2(N) - 9 + floor(log2(1 / cos(lat))) for the default
  // grid, clamped to the store's levels.
  int source_level(int z, double lat) const;
  // The extent (and bbox) the tiles cover, in the square world's latitudes.
  geo::GeoBox bounds() const;

  bool available(const XyzKey& key) const;
  // Every available tile of a zoom, sorted by (y, x).
  std::vector<XyzKey> available_tiles(int z) const;
  // TileJSON 2.2.0 for tiles at "{z}/{x}/{y}.EXTENSION" beside it;
  // `encoding` for a DEM (MapLibre reads "encoding" and "tileSize" from it).
  std::string tile_json(const std::string& name, std::optional<DemEncoding> encoding,
                        std::string_view extension = "png") const;

  // Elevation stores. Heights (metres) of the pixel centres, row-major from
  // the north-west, NaN where there is no data.
  Result<std::vector<double>> heights(const XyzKey& key) const;
  // The tile as an RGBA PNG: heights encoded, nodata as 0 m, alpha 255.
  Result<std::vector<std::byte>> dem_png_tile(const XyzKey& key, DemEncoding encoding) const;

  // Imagery stores. RGBA pixels, transparent where there is no data.
  Result<tiles::Raster> imagery_raster(const XyzKey& key) const;
  Result<std::vector<std::byte>> imagery_png_tile(const XyzKey& key) const;
  // Lossy colour at `quality` (1-100), lossless alpha: for orthoimagery a
  // fraction of the PNG's bytes.
  Result<std::vector<std::byte>> imagery_webp_tile(const XyzKey& key,
                                                   int quality = kWebpQuality) const;
  static constexpr int kWebpQuality = 85;

 private:
  struct Impl;
  explicit RasterTiler(std::unique_ptr<Impl> impl);
  std::unique_ptr<Impl> impl_;
};

// Heights as a PNG tile: an N x N RGBA image, N * N heights row-major.
Result<std::vector<std::byte>> encode_dem_png(const std::vector<double>& heights, int tile_size,
                                              DemEncoding encoding);

}  // namespace relief::web
