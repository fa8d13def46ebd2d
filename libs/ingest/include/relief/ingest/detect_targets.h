#pragma once
// `relief detect`: the point-target detector of the process library over a
// SAR amplitude raster GDAL reads (strip by strip, all cores), detections
// written as GeoJSON in WGS84, and optionally the analysis of one target as
// JSON and a PNG plot of its cross-sections.
#include <filesystem>
#include <optional>
#include <string>
#include <utility>

#include "relief/base/parallel.h"
#include "relief/base/progress.h"
#include "relief/base/result.h"
#include "relief/process/point_targets.h"

namespace relief::ingest {

struct DetectOptions {
  std::string input;
  std::filesystem::path geojson;
  process::DetectorParams detector;
  // Analysis of the detection nearest to this pixel (x, y) (default: the
  // strongest); written when either path is set.
  std::optional<std::pair<int, int>> analyse_at;
  std::filesystem::path analysis_json, analysis_png;
  int half_length = 32;  // cross-section samples either side of the peak
};

struct DetectReport {
  size_t detections = 0;
  double max_amplitude = 0;
  std::optional<process::TargetAnalysis> analysis;
};

Result<DetectReport> detect_targets(const DetectOptions& options, Executor& executor,
                                    Progress& progress);

}  // namespace relief::ingest
