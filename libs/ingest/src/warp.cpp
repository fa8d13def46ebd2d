#include "warp.h"

#include <cpl_string.h>
#include <gdal_utils.h>
#include <gdalwarper.h>

#include <algorithm>
#include <cmath>
#include <limits>

#include <fmt/format.h>

namespace relief::ingest {
namespace {

struct WarpOptionsDeleter {
  void operator()(GDALWarpAppOptions* o) const { GDALWarpAppOptionsFree(o); }
};
struct VrtOptionsDeleter {
  void operator()(GDALBuildVRTOptions* o) const { GDALBuildVRTOptionsFree(o); }
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

std::vector<MosaicGroup> group_sources(const std::vector<Source>& sources) {
  std::vector<MosaicGroup> groups;
  for (size_t i = 0; i < sources.size(); ++i) {
    const Source& s = sources[i];
    MosaicGroup* target = nullptr;
    if (s.north_up && !groups.empty()) {
      // Only join the most recent group, so later inputs still land on top.
      const Source& head = sources[groups.back().members.front()];
      if (head.north_up && head.crs_wkt == s.crs_wkt && head.mosaic_key == s.mosaic_key) {
        target = &groups.back();
      }
    }
    if (!target) {
      groups.push_back({{}, s.box});
      target = &groups.back();
    }
    target->members.push_back(i);
    geo::GeoBox& b = target->box;
    b = {std::min(b.west, s.box.west), std::min(b.south, s.box.south), std::max(b.east, s.box.east),
         std::max(b.north, s.box.north)};
  }
  return groups;
}

TileWarper::TileWarper(const std::vector<Source>& sources, const std::vector<MosaicGroup>& groups,
                       tiles::DatasetKind kind, geo::TileGrid grid, double error_threshold,
                       bool direct, SharedDirectSources* shared)
    : sources_(sources),
      groups_(groups),
      kind_(kind),
      grid_(grid),
      error_threshold_(error_threshold),
      direct_(direct && kind != tiles::DatasetKind::Imagery),
      shared_(shared),
      open_(groups.size()),
      direct_resamplers_(groups.size()),
      projected_(groups.size()) {}

ProjectedResampler* TileWarper::projected_for(size_t g) {
  if (!direct_) return nullptr;
  auto& slot = projected_[g];
  if (!slot) {
    // A group reaching past the antimeridian is left to GDAL's warper, which
    // handles the wrap; so is one GDAL cannot open.
    const geo::GeoBox& b = groups_[g].box;
    auto handle = group_handle(g);
    slot = handle && b.west >= -180.0 && b.east <= 180.0
               ? ProjectedResampler::create(*handle, error_threshold_)
               : std::optional<ProjectedResampler>();
  }
  return *slot ? &**slot : nullptr;
}

double TileWarper::scale_for(const geo::TileKey& key, const std::vector<size_t>& groups) const {
  double source_spacing = INFINITY;
  for (size_t g : groups) {
    for (size_t m : groups_[g].members)
      source_spacing = std::min(source_spacing, sources_[m].spacing_deg);
  }
  return std::min(1.0, source_spacing / grid_.sample_spacing(key.level));
}

const DirectResampler* TileWarper::direct_for(size_t g, int level) {
  if (!direct_) return nullptr;
  if (shared_) {
    return shared_->get(g, grid_.sample_spacing(level), [&] { return open_group(g); });
  }
  auto& slot = direct_resamplers_[g];
  if (!slot) {
    auto handle = group_handle(g);
    slot = handle ? DirectResampler::create(*handle, grid_.sample_spacing(level))
                  : std::optional<DirectResampler>();
  }
  return *slot ? &**slot : nullptr;
}

Result<tiles::Raster> TileWarper::warp_direct(const geo::TileKey& key,
                                              const std::vector<size_t>& groups) {
  if (groups.empty())
    return tiles::Raster::empty(tiles::SampleType::Float32, grid_.width(), grid_.height());
  // The first group covers every sample (nodata where it has none): no fill
  // beforehand, which cost a build a twentieth of its time.
  tiles::Raster r =
      tiles::Raster::uninitialised(tiles::SampleType::Float32, 1, grid_.width(), grid_.height());
  for (size_t g : groups)
    RELIEF_CHECK(direct_for(g, key.level)->resample(grid_, key, r, g == groups.front()));
  return r;
}

std::vector<size_t> TileWarper::groups_for(const geo::TileKey& key) const {
  // Pad by two samples so bilinear support at the tile edge is never cut off.
  geo::GeoBox b = key.bounds();
  const double pad = 2 * grid_.sample_spacing(key.level);
  b = {b.west - pad, b.south - pad, b.east + pad, b.north + pad};
  std::vector<size_t> hits;
  for (size_t g = 0; g < groups_.size(); ++g) {
    if (boxes_meet(b, groups_[g].box)) hits.push_back(g);
  }
  return hits;
}

Result<GDALDatasetH> TileWarper::group_handle(size_t g) {
  if (!open_[g]) open_[g] = RELIEF_TRY(open_group(g));
  return open_[g].get();
}

Result<Dataset> TileWarper::open_group(size_t g) const {
  const MosaicGroup& group = groups_[g];
  const Source& first = sources_[group.members.front()];
  Dataset ds;
  if (group.members.size() == 1) {
    ds = open_raster(first.open_path());
  } else {
    std::vector<const char*> paths;
    for (size_t m : group.members) paths.push_back(sources_[m].open_path().c_str());
    // Keep the finest input resolution; later inputs are drawn on top.
    const char* argv[] = {"-resolution", "highest", nullptr};
    std::unique_ptr<GDALBuildVRTOptions, VrtOptionsDeleter> options(
        GDALBuildVRTOptionsNew(const_cast<char**>(argv), nullptr));
    int usage_error = 0;
    CPLErrorReset();
    ds = Dataset(GDALBuildVRT("", static_cast<int>(paths.size()), nullptr, paths.data(),
                              options.get(), &usage_error));
    // The VRT builder skips a file it cannot mosaic with a warning only: that
    // would silently drop an input's data.
    if (ds) {
      char** files = GDALGetFileList(ds.get());
      for (size_t m : group.members) {
        if (CSLFindString(files, sources_[m].open_path().c_str()) < 0) {
          CSLDestroy(files);
          return fail(fmt::format("{}: cannot be mosaicked with {}: {}", sources_[m].path,
                                  first.path, gdal_error("left out of the mosaic")));
        }
      }
      CSLDestroy(files);
    }
  }
  if (!ds) return fail(fmt::format("{}: {}", first.path, gdal_error("cannot open for reading")));
  // --src-crs may have supplied a CRS the file lacks.
  if (!first.crs_wkt.empty()) GDALSetProjection(ds.get(), first.crs_wkt.c_str());
  return ds;
}

Result<tiles::Raster> TileWarper::warp(const geo::TileKey& key) {
  const bool imagery = kind_ == tiles::DatasetKind::Imagery;
  const int w = grid_.width(), h = grid_.height();
  auto hits = groups_for(key);
  if (hits.empty())
    return tiles::Raster::empty(imagery ? tiles::SampleType::UInt8 : tiles::SampleType::Float32, w,
                                h);

  if (std::all_of(hits.begin(), hits.end(), [&](size_t g) { return direct_for(g, key.level); })) {
    return warp_direct(key, hits);
  }
  if (!imagery &&
      std::all_of(hits.begin(), hits.end(), [&](size_t g) { return projected_for(g); })) {
    tiles::Raster r = tiles::Raster::empty(tiles::SampleType::Float32, w, h);
    const double scale = scale_for(key, hits);
    bool handled = true;
    for (size_t g : hits) {
      handled = RELIEF_TRY(projected_for(g)->resample(grid_, key, scale, r));
      if (!handled) break;  // the whole tile goes to GDAL's warper
    }
    if (handled) return r;
  }

  std::vector<GDALDatasetH> handles;
  for (size_t g : hits) {
    auto hnd = group_handle(g);
    if (!hnd) return std::unexpected(hnd.error());
    handles.push_back(*hnd);
  }

  // Destination: the tile interior as an in-memory dataset on the WGS84 grid.
  const int colour = imagery ? sources_.front().colour_bands : 1;
  const int dst_bands = imagery ? colour + 1 : 1;
  GDALDriverH mem = GDALGetDriverByName("MEM");
  Dataset dst(GDALCreate(mem, "", w, h, dst_bands, imagery ? GDT_Byte : GDT_Float32, nullptr));
  if (!dst)
    return fail(fmt::format("tile {}: cannot allocate: {}", key.to_string(), gdal_error("MEM")));
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
  const std::string threshold = fmt::format("{}", error_threshold_);
  // GDAL derives the resampling scale per chunk from the shape of the source
  // window, which for rotated or reprojected inputs varies between tiles and
  // would make neighbouring tiles interpolate differently. Fix it from the
  // resolutions instead: plain 2 x 2 bilinear (or 4 x 4 cubic) when upsampling,
  // which is what a build does unless --max-level asks for a coarser level.
  const double scale = scale_for(key, hits);
  const std::string xscale = fmt::format("XSCALE={}", scale),
                    yscale = fmt::format("YSCALE={}", scale);
  std::vector<const char*> args = {"-r",  imagery ? "cubic" : "bilinear",
                                   "-et", threshold.c_str(),
                                   "-wo", xscale.c_str(),
                                   "-wo", yscale.c_str(),
                                   "-q"};
  if (imagery)
    args.push_back("-dstalpha");
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
    return fail(fmt::format("{}: reprojection to tile {} failed: {}",
                            sources_[groups_[hits[0]].members[0]].path, key.to_string(),
                            gdal_error("unknown GDAL error")));
  }

  tiles::Raster r =
      tiles::Raster::empty(imagery ? tiles::SampleType::UInt8 : tiles::SampleType::Float32, w, h);
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
