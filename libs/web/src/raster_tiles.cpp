#include "relief/web/raster_tiles.h"

#include <algorithm>
#include <bit>
#include <cmath>
#include <cstring>
#include <numbers>

#include <fmt/format.h>
#include <nlohmann/json.hpp>

#include "mercator_resample.h"
#include "relief/tiles/codec.h"
#include "relief/tiles/store.h"
#include "sample_block.h"

namespace relief::web {

struct RasterTiler::Impl {
  std::shared_ptr<const tiles::Store> store;
  RasterTileOptions options;
  bool elevation = true;
  ResampleSource source;
  geo::GeoBox bounds;  // extent ∩ bbox ∩ the square world
  int max_zoom = 0;
  // One of the two, by the store's sample type.
  std::optional<SampleBlocks> heights;
  std::optional<PixelBlocks> pixels;

  std::string name() const { return store->root().string(); }
};

namespace {

Status check_store(const tiles::Manifest& m, const std::string& name) {
  const bool elevation = m.kind == tiles::DatasetKind::Elevation &&
                         m.sample_type == tiles::SampleType::Float32 && m.bands == 1;
  const bool imagery = m.kind == tiles::DatasetKind::Imagery &&
                       m.sample_type == tiles::SampleType::UInt8 && m.bands == 4;
  if (elevation || imagery) return {};
  return fail(fmt::format("{}: holds {}: web raster tiles need an elevation or an imagery store",
                          name, tiles::to_string(m.kind)));
}

// The box's latitude nearest the equator.
double nearest_equator(const geo::GeoBox& b) {
  if (b.south <= 0 && b.north >= 0) return 0;
  return b.south > 0 ? b.south : b.north;
}

}  // namespace

RasterTiler::RasterTiler(std::unique_ptr<Impl> impl) : impl_(std::move(impl)) {}
RasterTiler::~RasterTiler() = default;
RasterTiler::RasterTiler(RasterTiler&&) noexcept = default;
RasterTiler& RasterTiler::operator=(RasterTiler&&) noexcept = default;

Result<RasterTiler> RasterTiler::create(std::shared_ptr<const tiles::Store> store,
                                        RasterTileOptions options) {
  const tiles::Manifest& m = store->manifest();
  const std::string name = store->root().string();
  RELIEF_CHECK(check_store(m, name));
  if (options.tile_size != 256 && options.tile_size != 512) {
    return fail(fmt::format("tile size {}: web raster tiles are 256 or 512 pixels a side",
                            options.tile_size));
  }
  if (options.max_zoom > kMaxZoom) {
    return fail(
        fmt::format("max zoom {}: XYZ tiles go to zoom {} at most", options.max_zoom, kMaxZoom));
  }
  auto impl = std::make_unique<Impl>();
  impl->elevation = m.kind == tiles::DatasetKind::Elevation;
  impl->source = {store->grid().log2_height(), m.min_level, m.max_level, m.extent};
  geo::GeoBox b{std::max(m.extent.west, -180.0), std::max(m.extent.south, -kMercatorMaxLatitude),
                std::min(m.extent.east, 180.0), std::min(m.extent.north, kMercatorMaxLatitude)};
  if (options.bbox) {
    b = {std::max(b.west, options.bbox->west), std::max(b.south, options.bbox->south),
         std::min(b.east, options.bbox->east), std::min(b.north, options.bbox->north)};
  }
  if (!(b.west < b.east && b.south < b.north)) {
    return fail(options.bbox ? fmt::format("the bbox does not meet the extent of {}", name)
                             : fmt::format("{}: no data within the Web Mercator world", name));
  }
  impl->bounds = b;
  if (impl->elevation) {
    impl->heights.emplace(store, options.cache_bytes);
  } else {
    impl->pixels.emplace(store, options.cache_bytes);
  }
  impl->store = std::move(store);
  impl->options = std::move(options);
  RasterTiler tiler(std::move(impl));
  tiler.impl_->max_zoom =
      tiler.impl_->options.max_zoom < 0 ? tiler.natural_max_zoom() : tiler.impl_->options.max_zoom;
  return tiler;
}

bool RasterTiler::holds_elevation() const {
  return impl_->elevation;
}
int RasterTiler::tile_size() const {
  return impl_->options.tile_size;
}
int RasterTiler::max_zoom() const {
  return impl_->max_zoom;
}
geo::GeoBox RasterTiler::bounds() const {
  return impl_->bounds;
}

int RasterTiler::natural_max_zoom() const {
  // source_level grows with z and with |lat|: the extent's latitude nearest
  // the equator is the last to reach the finest level.
  const ResampleSource& s = impl_->source;
  const double c = std::cos(nearest_equator(impl_->bounds) * std::numbers::pi / 180);
  const int finer = static_cast<int>(std::floor(-std::log2(c)));
  const int log2_size = std::countr_zero(static_cast<unsigned>(tile_size()));
  return std::max(0, s.max_level + s.log2_tile_height + 1 - log2_size - finer);
}

int RasterTiler::source_level(int z, double lat) const {
  return web::source_level(impl_->source, z, tile_size(), lat);
}

bool RasterTiler::available(const XyzKey& key) const {
  if (key.z < 0 || key.z > impl_->max_zoom || !key.valid()) return false;
  const auto range = xyz_tiles_meeting(key.z, impl_->bounds);
  return range && key.x >= range->x0 && key.x <= range->x1 && key.y >= range->y0 &&
         key.y <= range->y1;
}

std::vector<XyzKey> RasterTiler::available_tiles(int z) const {
  std::vector<XyzKey> keys;
  if (z < 0 || z > impl_->max_zoom) return keys;
  const auto range = xyz_tiles_meeting(z, impl_->bounds);
  if (!range) return keys;
  for (uint32_t y = range->y0; y <= range->y1; ++y) {
    for (uint32_t x = range->x0; x <= range->x1; ++x) keys.push_back({z, x, y});
  }
  return keys;
}

std::string RasterTiler::tile_json(const std::string& name, std::optional<DemEncoding> encoding,
                                   std::string_view extension) const {
  const geo::GeoBox& b = impl_->bounds;
  nlohmann::json j = {
      {"tilejson", "2.2.0"},
      {"name", name},
      {"description",
       encoding ? fmt::format("relief {} heights of an elevation store", format_name(*encoding))
                : std::string("relief imagery")},
      {"version", "1.0.0"},
      {"scheme", "xyz"},
      {"tiles", {fmt::format("{{z}}/{{x}}/{{y}}.{}", extension)}},
      {"minzoom", 0},
      {"maxzoom", impl_->max_zoom},
      {"bounds", {b.west, b.south, b.east, b.north}},
      {"tileSize", tile_size()},
  };
  if (encoding) j["encoding"] = maplibre_name(*encoding);
  return j.dump(1);
}

Result<std::vector<double>> RasterTiler::heights(const XyzKey& key) const {
  if (!impl_->elevation) return fail(fmt::format("{}: holds imagery, not heights", impl_->name()));
  if (!available(key)) return fail(fmt::format("web tile {}: not available", key.to_string()));
  return resample_heights(*impl_->heights, impl_->source, key, tile_size());
}

Result<std::vector<std::byte>> RasterTiler::dem_png_tile(const XyzKey& key,
                                                         DemEncoding encoding) const {
  return encode_dem_png(RELIEF_TRY(heights(key)), tile_size(), encoding);
}

Result<tiles::Raster> RasterTiler::imagery_raster(const XyzKey& key) const {
  if (impl_->elevation) {
    return fail(fmt::format("{}: holds elevation, not imagery", impl_->name()));
  }
  if (!available(key)) return fail(fmt::format("web tile {}: not available", key.to_string()));
  const std::vector<Rgba> pixels =
      RELIEF_TRY(resample_pixels(*impl_->pixels, impl_->source, key, tile_size()));
  tiles::Raster r =
      tiles::Raster::uninitialised(tiles::SampleType::UInt8, 4, tile_size(), tile_size());
  std::memcpy(r.u8().data(), pixels.data(), pixels.size() * sizeof(Rgba));
  return r;
}

namespace {
Result<std::vector<std::byte>> encode_as(const tiles::Raster& r, tiles::Codec codec,
                                         int quality = 90) {
  tiles::CodecOptions o;
  o.codec = codec;
  o.quality = quality;
  return tiles::encode(r, o);
}
Result<std::vector<std::byte>> encode_png(const tiles::Raster& r) {
  return encode_as(r, tiles::Codec::Png);
}
}  // namespace

Result<std::vector<std::byte>> RasterTiler::imagery_png_tile(const XyzKey& key) const {
  return encode_png(RELIEF_TRY(imagery_raster(key)));
}

Result<std::vector<std::byte>> RasterTiler::imagery_webp_tile(const XyzKey& key,
                                                              int quality) const {
  return encode_as(RELIEF_TRY(imagery_raster(key)), tiles::Codec::Webp, quality);
}

Result<std::vector<std::byte>> encode_dem_png(const std::vector<double>& heights, int tile_size,
                                              DemEncoding encoding) {
  tiles::Raster r = tiles::Raster::uninitialised(tiles::SampleType::UInt8, 4, tile_size, tile_size);
  const std::span<uint8_t> out = r.u8();
  if (heights.size() * 4 != out.size()) {
    return fail(
        fmt::format("{} heights do not fill a {} x {} tile", heights.size(), tile_size, tile_size));
  }
  for (size_t p = 0; p < heights.size(); ++p) {
    const Rgb rgb = encode_height(encoding, heights[p]);
    out[4 * p] = rgb.r, out[4 * p + 1] = rgb.g, out[4 * p + 2] = rgb.b, out[4 * p + 3] = 255;
  }
  return encode_png(r);
}

}  // namespace relief::web
