#pragma once
// `relief export`: reassembles one pyramid level (or a window of it) into a
// GeoTIFF on the store's WGS84 sample grid, tile interiors only.
#include <cstdint>
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
  // The whole process: GDAL's cache of the output's blocks gets what is left
  // after export_reserve() (without a cap it held every block of the output,
  // 1.3 GB for a 1.07 GB raster).
  uint64_t memory_budget = uint64_t{256} << 20;
};

// What the process takes besides GDAL's block cache: its code, libraries and
// one tile (63 MiB measured), and an eighth of the budget for the cache's own
// overhead and the allocator's slack.
constexpr uint64_t export_reserve(uint64_t budget) {
  return (uint64_t{64} << 20) + budget / 8;
}
// Leaves a cache of at least 16 MiB.
constexpr uint64_t kExportMinimumBudget = uint64_t{96} << 20;

struct ExportReport {
  int width = 0, height = 0;
  int tiles_read = 0;
};

Result<ExportReport> export_geotiff(const ExportOptions& options, Progress& progress);

}  // namespace relief::ingest
