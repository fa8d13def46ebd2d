#pragma once
// `relief process IN.tif -o OUT.tif --op NAME`: runs a raster operator of the
// process library over a raster GDAL reads, strip by strip (out of core), and
// writes a tiled Float32 GeoTIFF with the input's georeferencing.
#include <cstdint>
#include <filesystem>
#include <string>
#include <vector>

#include "relief/base/parallel.h"
#include "relief/base/progress.h"
#include "relief/base/result.h"

namespace relief::ingest {

struct ProcessRasterOptions {
  std::string input;
  std::filesystem::path output;
  std::string op;
  std::vector<std::string> params;  // "key=value"
  uint64_t memory_budget = uint64_t{1} << 30;
  std::string compress = "none";  // GeoTIFF compression: none, deflate, zstd
};

struct ProcessRasterReport {
  int width = 0, height = 0;
  double seconds = 0;
};

Result<ProcessRasterReport> process_raster(const ProcessRasterOptions& options, Executor& executor,
                                           Progress& progress);

}  // namespace relief::ingest
