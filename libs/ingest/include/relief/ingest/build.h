#pragma once
// `relief build`: turns rasters GDAL can read into a tile pyramid store.
//
// Steps (each parallel over tiles, each resumable after a crash):
//  0. voids    with --fill-voids, elevation sources with holes are copied with
//              the holes filled (void_fill.h)
//  1. warp     every finest-level tile interior is resampled from the sources
//              (GDAL warper; bilinear for elevation/SAR, cubic for imagery)
//  2. pyramid  coarser interiors by nodata-aware 2 x 2 averaging
//  3. tiles    bordered tiles assembled from the 3 x 3 neighbouring interiors,
//              so borders equal the neighbours' samples exactly; encoded and
//              written atomically with per-tile statistics
//  Steps 1-3 are one graph of tasks on the workers: a parent interior is made
//  once its four children exist, a tile written once its neighbourhood exists.
//  4. geometric errors (elevation), indices, and the manifest, written last:
//     a store with a manifest is complete.
// Interiors live in <store>/.build until the build finishes.
#include <cstdint>
#include <filesystem>
#include <functional>
#include <optional>
#include <string>
#include <vector>

#include "relief/base/parallel.h"
#include "relief/base/progress.h"
#include "relief/base/result.h"
#include "relief/tiles/manifest.h"

namespace relief::ingest {

struct BuildOptions {
  std::vector<std::string> inputs;
  std::filesystem::path output;
  tiles::DatasetKind kind = tiles::DatasetKind::Elevation;
  std::optional<int> min_level;       // default 0
  std::optional<int> max_level;       // default: next level finer than the finest source
  std::optional<tiles::Codec> codec;  // default: zstd (lerc if max_error > 0); jpeg for imagery
  double max_error = 0;               // LERC maximum absolute error
  int quality = 90;                   // JPEG / WebP
  int tile_log2_height = 8;
  int border = 9;
  uint64_t memory_budget = uint64_t{1} << 30;
  // Hands freed pages the allocator holds back to the system (the program's
  // allocator knows how): called when the process nears memory_budget.
  std::function<void()> release_freed_memory;
  bool overwrite = false;
  std::optional<std::string> src_crs;  // for inputs without a CRS
  double warp_error = 0.125;      // approximate-transform error in source pixels (gdalwarp -et)
  bool direct_resampling = true;  // fast path for WGS84 lon/lat inputs (same result as GDAL)
  bool fill_voids = false;        // elevation: fill nodata holes (see void_fill.h)
};

struct BuildReport {
  tiles::Manifest manifest;
  uint64_t tiles_written = 0;
  uint64_t tiles_resumed = 0;  // already present from an interrupted run
  uint64_t voids_filled = 0;   // source samples filled by --fill-voids
  double seconds = 0;
  std::vector<std::pair<std::string, double>> phase_seconds;  // wall time per phase
};

Result<BuildReport> build_store(const BuildOptions& options, Executor& executor,
                                Progress& progress);

}  // namespace relief::ingest
