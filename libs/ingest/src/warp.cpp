#include "warp.h"

#include <gdal_utils.h>
#include <gdalwarper.h>

#include <cmath>
#include <limits>

#include <fmt/format.h>

namespace relief::ingest {
namespace {

constexpr size_t kMaxOpenSources = 64;

const char* kWgs84Wkt =
    R"(GEOGCS["WGS 84",DATUM["WGS_1984",SPHEROID["WGS 84",6378137,298.257223563]],PRIMEM["Greenwich",0],UNIT["degree",0.0174532925199433],AUTHORITY["EPSG","4326"]])";

struct WarpOptionsDeleter {
  void operator()(GDALWarpAppOptions* o) const { GDALWarpAppOptionsFree(o); }
};

bool boxes_meet(const geo::GeoBox& tile, const geo::GeoBox& src) {
  // The source box may extend past +-180; compare against the tile shifted by 360.
  for (double shift : {-360.0, 0.0, 360.0}) {
    geo::GeoBox t{tile.west + shift, tile.south, tile.east + shift, tile.north};
    if (t.intersects(src)) return true;
  }
  return false;
}

}  // namespace

TileWarper::TileWarper(const std::vector<Source>& sources, tiles::DatasetKind kind,
                       geo::TileGrid grid)
    : sources_(sources), kind_(kind), grid_(grid) {}

std::vector<size_t> TileWarper::sources_for(const geo::TileKey& key) const {
  // Pad by two samples so bilinear support at the tile edge is never cut off.
  geo::GeoBox b = key.bounds();
  const double pad = 2 * grid_.sample_spacing(key.level);
  b = {b.west - pad, b.south - pad, b.east + pad, b.north + pad};
  std::vector<size_t> hits;
  for (size_t i = 0; i < sources_.size(); ++i) {
    if (boxes_meet(b, sources_[i].box)) hits.push_back(i);
  }
  return hits;
}

Result<GDALDatasetH> TileWarper::source_handle(size_t i) {
  if (auto it = open_.find(i); it != open_.end()) return it->second.get();
  if (open_.size() >= kMaxOpenSources) open_.clear();
  Dataset ds = open_raster(sources_[i].path);
  if (!ds) return fail(fmt::format("{}: {}", sources_[i].path, gdal_error("cannot reopen")));
  if (!sources_[i].crs_wkt.empty()) GDALSetProjection(ds.get(), sources_[i].crs_wkt.c_str());
  GDALDatasetH h = ds.get();
  open_.emplace(i, std::move(ds));
  return h;
}

Result<tiles::Raster> TileWarper::warp(const geo::TileKey& key) {
  const bool imagery = kind_ == tiles::DatasetKind::Imagery;
  const int w = grid_.width(), h = grid_.height();
  auto hits = sources_for(key);
  if (hits.empty()) return tiles::Raster::empty(imagery ? tiles::SampleType::UInt8 : tiles::SampleType::Float32, w, h);

  std::vector<GDALDatasetH> handles;
  for (size_t i : hits) {
    auto hnd = source_handle(i);
    if (!hnd) return std::unexpected(hnd.error());
    handles.push_back(*hnd);
  }

  // Destination: the tile interior as an in-memory dataset on the WGS84 grid.
  const int colour = imagery ? sources_[hits[0]].colour_bands : 1;
  const int dst_bands = imagery ? colour + 1 : 1;
  GDALDriverH mem = GDALGetDriverByName("MEM");
  Dataset dst(GDALCreate(mem, "", w, h, dst_bands, imagery ? GDT_Byte : GDT_Float32, nullptr));
  if (!dst) return fail(fmt::format("tile {}: cannot allocate: {}", key.to_string(), gdal_error("MEM")));
  const geo::GeoBox b = key.bounds();
  const double d = grid_.sample_spacing(key.level);
  double gt[6] = {b.west, d, 0, b.north, 0, -d};
  GDALSetGeoTransform(dst.get(), gt);
  GDALSetProjection(dst.get(), kWgs84Wkt);
  if (imagery) {
    GDALSetRasterColorInterpretation(GDALGetRasterBand(dst.get(), dst_bands), GCI_AlphaBand);
  } else {
    GDALRasterBandH band = GDALGetRasterBand(dst.get(), 1);
    GDALSetRasterNoDataValue(band, std::numeric_limits<double>::quiet_NaN());
    GDALFillRaster(band, std::numeric_limits<double>::quiet_NaN(), 0);
  }

  // Bilinear for continuous fields (elevation, SAR); cubic for imagery, which
  // keeps upsampled photographs sharper and is clamped to 0..255 by GDAL.
  // No INIT_DEST: it would re-initialise the tile for every source and erase
  // the earlier ones. The destination starts as nodata (NaN or alpha 0).
  std::vector<const char*> args = {"-r", imagery ? "cubic" : "bilinear",
                                   "-q"};
  if (imagery) args.push_back("-dstalpha");
  else {
    args.insert(args.end(), {"-dstnodata", "nan"});
  }
  args.push_back(nullptr);
  std::unique_ptr<GDALWarpAppOptions, WarpOptionsDeleter> options(
      GDALWarpAppOptionsNew(const_cast<char**>(args.data()), nullptr));
  if (!options) return fail("internal: bad warp options");
  int usage_error = 0;
  CPLErrorReset();
  GDALDatasetH out = GDALWarp(nullptr, dst.get(), static_cast<int>(handles.size()), handles.data(),
                              options.get(), &usage_error);
  if (!out || usage_error) {
    return fail(fmt::format("{}: reprojection to tile {} failed: {}", sources_[hits[0]].path,
                            key.to_string(), gdal_error("unknown GDAL error")));
  }

  tiles::Raster r = tiles::Raster::empty(imagery ? tiles::SampleType::UInt8 : tiles::SampleType::Float32, w, h);
  if (!imagery) {
    if (GDALRasterIO(GDALGetRasterBand(dst.get(), 1), GF_Read, 0, 0, w, h, r.f32().data(), w, h,
                     GDT_Float32, 0, 0) != CE_None) {
      return fail(fmt::format("tile {}: {}", key.to_string(), gdal_error("read-back failed")));
    }
    return r;
  }
  // Imagery: read colour (grey replicated to RGB) and alpha into interleaved RGBA.
  std::vector<int> band_map;
  for (int c = 0; c < 3; ++c) band_map.push_back(colour == 1 ? 1 : c + 1);
  band_map.push_back(dst_bands);
  if (GDALDatasetRasterIO(dst.get(), GF_Read, 0, 0, w, h, r.u8().data(), w, h, GDT_Byte, 4,
                          band_map.data(), 4, 4 * w, 1) != CE_None) {
    return fail(fmt::format("tile {}: {}", key.to_string(), gdal_error("read-back failed")));
  }
  return r;
}

}  // namespace relief::ingest
