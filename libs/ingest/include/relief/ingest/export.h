#pragma once
// `relief export`: reassembles one pyramid level (or a window of it) into a
// GeoTIFF on the store's WGS84 sample grid, tile interiors only.
#include <filesystem>
#include <optional>

#include "relief/base/progress.h"
#include "relief/base/result.h"
#include "relief/geo/tile_key.h"

namespace relief::ingest {

struct ExportOptions {
  std::filesystem::path store;
  int level = 0;
  std::optional<geo::GeoBox> bbox;  // default: the dataset's extent
  std::filesystem::path output;
};

struct ExportReport {
  int width = 0, height = 0;
  int tiles_read = 0;
};

Result<ExportReport> export_geotiff(const ExportOptions& options, Progress& progress);

}  // namespace relief::ingest
