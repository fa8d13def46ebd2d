#pragma once
// GDAL plumbing private to ingest: one-time driver registration, quiet error
// handling (GDAL's messages are turned into Error values), and RAII handles.
#include <gdal.h>

#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "relief/base/result.h"

namespace relief::ingest {

// WGS84 geographic coordinates (EPSG:4326), longitude first: the store's CRS.
inline constexpr const char* kWgs84Wkt =
    R"(GEOGCS["WGS 84",DATUM["WGS_1984",SPHEROID["WGS 84",6378137,298.257223563]],PRIMEM["Greenwich",0],UNIT["degree",0.0174532925199433],AUTHORITY["EPSG","4326"]])";

// Registers drivers and silences GDAL's stderr output. Safe to call often.
void init_gdal();
// The last GDAL error message of this thread, or `fallback` when there is none.
std::string gdal_error(const std::string& fallback);

struct DatasetCloser {
  void operator()(GDALDatasetH h) const {
    if (h) GDALClose(h);
  }
};
using Dataset = std::unique_ptr<std::remove_pointer_t<GDALDatasetH>, DatasetCloser>;

// Opens a raster read-only; nullptr on failure (see gdal_error()).
Dataset open_raster(const std::string& path);

// Reads the window [x0 - margin, x0 + w + margin) x [y0 - margin, y0 + h + margin)
// of a band as Float32 into `out` (row stride w + 2 margin); samples outside
// the raster and the band's nodata value become NaN. Returns an error naming
// `name` on failure.
std::optional<std::string> read_padded(GDALRasterBandH band, int x0, int y0, int w, int h,
                                       int margin, std::vector<float>& out,
                                       const std::string& name);

// Opens a raster that must have exactly one real-valued band (amplitudes,
// elevations); the errors name `path`.
struct SingleBand {
  Dataset dataset;
  GDALRasterBandH band = nullptr;
};
Result<SingleBand> open_single_band(const std::string& path);

// Closes `out` (written at `tmp`), which flushes it, and renames it to
// `final_path`; on any failure (a full disk shows up at the flush) the
// temporary file is removed and the error names `final_path`.
std::optional<std::string> finish_atomic_write(Dataset& out, const std::string& tmp,
                                               const std::string& final_path);

}  // namespace relief::ingest
