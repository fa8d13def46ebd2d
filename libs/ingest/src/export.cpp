#include "relief/ingest/export.h"

#include <cpl_conv.h>
#include <gdal.h>
#include <unistd.h>

#include <cmath>
#include <limits>

#include <fmt/format.h>

#include "gdal_env.h"
#include "relief/base/file_io.h"
#include "relief/base/units.h"
#include "relief/tiles/store.h"

namespace relief::ingest {
namespace fs = std::filesystem;

namespace {
constexpr int64_t kMaxExportSamples = int64_t{1} << 34;  // 16 Gi samples
}  // namespace

Result<ExportReport> export_geotiff(const ExportOptions& o, Progress& progress) {
  auto store = tiles::Store::open(o.store);
  if (!store) return std::unexpected(store.error());
  const tiles::Manifest& m = store->manifest();
  if (o.level < m.min_level || o.level > m.max_level) {
    return fail(fmt::format("--level: {} is not in the store's range {}..{}", o.level, m.min_level,
                            m.max_level));
  }
  const geo::GeoBox box = o.bbox.value_or(m.extent);
  if (!(box.west < box.east && box.south < box.north) || box.west < -180 || box.east > 180 ||
      box.south < -90 || box.north > 90) {
    return fail(fmt::format("--bbox: {},{},{},{} is not a box inside -180,-90,180,90", box.west,
                            box.south, box.east, box.north));
  }
  const geo::TileGrid& grid = store->grid();
  const double d = grid.sample_spacing(o.level);
  // Global sample indices covering the box, snapped outwards to the sample grid.
  const int64_t i0 = static_cast<int64_t>(std::floor((box.west + 180.0) / d + 1e-9));
  const int64_t i1 = static_cast<int64_t>(std::ceil((box.east + 180.0) / d - 1e-9));
  const int64_t j0 = static_cast<int64_t>(std::floor((90.0 - box.north) / d + 1e-9));
  const int64_t j1 = static_cast<int64_t>(std::ceil((90.0 - box.south) / d - 1e-9));
  const int64_t width = i1 - i0, height = j1 - j0;
  if (width <= 0 || height <= 0 || width * height > kMaxExportSamples || width > INT32_MAX ||
      height > INT32_MAX) {
    return fail(
        fmt::format("--bbox: gives a {} x {} raster at level {}; choose a smaller box or level",
                    width, height, o.level));
  }

  if (o.memory_budget < kExportMinimumBudget) {
    return fail(fmt::format("--memory: {} is below the least an export needs ({})",
                            format_bytes(o.memory_budget), format_bytes(kExportMinimumBudget)));
  }
  init_gdal();
  // Blocks are written row of tiles by row of tiles: a full cache flushes the
  // oldest, which are complete.
  GDALSetCacheMax64(static_cast<GIntBig>(o.memory_budget - export_reserve(o.memory_budget)));
  const bool imagery = m.sample_type == tiles::SampleType::UInt8;
  const int bands = imagery ? 4 : 1;
  static_cast<void>(remove_stale_temporaries_of(o.output));  // of killed runs
  const std::string tmp = o.output.string() + std::string(kTempMarker) + std::to_string(::getpid());
  const char* create_options[] = {"TILED=YES",
                                  "COMPRESS=DEFLATE",
                                  "BIGTIFF=IF_SAFER",
                                  imagery ? "PHOTOMETRIC=RGB" : "PREDICTOR=3",
                                  imagery ? "ALPHA=UNASSOCIATED" : nullptr,
                                  nullptr};
  GDALDriverH gtiff = GDALGetDriverByName("GTiff");
  Dataset out(GDALCreate(gtiff, tmp.c_str(), static_cast<int>(width), static_cast<int>(height),
                         bands, imagery ? GDT_Byte : GDT_Float32,
                         const_cast<char**>(create_options)));
  if (!out)
    return fail(fmt::format("{}: cannot create: {}", o.output.string(), gdal_error("GTiff")));
  double gt[6] = {-180.0 + static_cast<double>(i0) * d, d, 0,
                  90.0 - static_cast<double>(j0) * d,   0, -d};
  GDALSetGeoTransform(out.get(), gt);
  GDALSetProjection(out.get(), kWgs84Wkt);
  if (!imagery) {
    // Blocks no tile writes are filled with the nodata value when the file is
    // closed (GTiff's empty blocks): no fill of the whole raster beforehand,
    // which wrote every block twice and held them all in the cache.
    GDALSetRasterNoDataValue(GDALGetRasterBand(out.get(), 1),
                             std::numeric_limits<double>::quiet_NaN());
  }
  auto discard = [&](Error e) -> Result<ExportReport> {
    out.reset();
    ::unlink(tmp.c_str());
    return std::unexpected(std::move(e));
  };

  const int w = grid.width(), h = grid.height(), b = grid.border();
  const int64_t tx0 = i0 / w, tx1 = (i1 - 1) / w, ty0 = j0 / h, ty1 = (j1 - 1) / h;
  ExportReport report{static_cast<int>(width), static_cast<int>(height), 0};
  progress.begin(fmt::format("export level {}", o.level),
                 static_cast<uint64_t>((tx1 - tx0 + 1) * (ty1 - ty0 + 1)));
  for (int64_t ty = ty0; ty <= ty1; ++ty) {
    for (int64_t tx = tx0; tx <= tx1; ++tx) {
      progress.advance();
      const geo::TileKey key{o.level, static_cast<uint32_t>(tx), static_cast<uint32_t>(ty)};
      if (!store->has_tile(key)) continue;
      auto tile = store->read_tile(key);
      if (!tile) return discard(tile.error());
      // Window of this tile's interior inside the output.
      const int64_t gx0 = std::max(i0, tx * w), gx1 = std::min(i1, (tx + 1) * w);
      const int64_t gy0 = std::max(j0, ty * h), gy1 = std::min(j1, (ty + 1) * h);
      const int cw = static_cast<int>(gx1 - gx0), ch = static_cast<int>(gy1 - gy0);
      const int sx = static_cast<int>(gx0 - tx * w) + b, sy = static_cast<int>(gy0 - ty * h) + b;
      tiles::Raster window(tile->raster.type(), tile->raster.bands(), cw, ch);
      window.copy_from(tile->raster, sx, sy, 0, 0, cw, ch);
      int band_map[4] = {1, 2, 3, 4};
      const CPLErr err = GDALDatasetRasterIO(
          out.get(), GF_Write, static_cast<int>(gx0 - i0), static_cast<int>(gy0 - j0), cw, ch,
          window.bytes().data(), cw, ch, imagery ? GDT_Byte : GDT_Float32, bands, band_map,
          /*pixel space*/ 4, /*line space*/ 4 * cw, /*band space*/ imagery ? 1 : 0);
      if (err != CE_None) {
        return discard(
            Error{fmt::format("{}: write failed: {}", o.output.string(), gdal_error("GTiff"))});
      }
      ++report.tiles_read;
    }
  }
  progress.end();
  if (auto error = finish_atomic_write(out, tmp, o.output.string())) return fail(*error);
  return report;
}

}  // namespace relief::ingest
