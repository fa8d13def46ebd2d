#pragma once
// `relief fuse`: combines several stores of the same kind tile by tile into
// one (seed 003 §1.3.3). All stores share the global quadtree grid, so tiles
// line up exactly; nodata in one input leaves the others to fill in. The
// per-tile min/max bounds of the result's level index come from the inputs'
// indices, without scanning the fused samples.
#include <filesystem>
#include <vector>

#include "relief/base/parallel.h"
#include "relief/base/progress.h"
#include "relief/base/result.h"
#include "relief/pipeline/fuse_tiles.h"

namespace relief::pipeline {

struct FuseOptions {
  std::vector<std::filesystem::path> inputs;  // at least two
  std::vector<double> weights;                // one per input, > 0; empty: all 1
  FuseMode mode = FuseMode::Blend;
  std::filesystem::path output;  // must not exist yet
  // An input that stops at a coarser level than another is upsampled to the
  // finest level over its whole extent: a global DEM fused with a local one
  // would become terabytes of interpolated tiles. Refused (before anything is
  // written) when the upsampled tiles outnumber the inputs' own tiles more
  // than 4 times, unless allowed.
  bool allow_upsampling = false;
};

struct FuseReport {
  uint64_t tiles = 0;
  int levels = 0;
};

Result<FuseReport> fuse_stores(const FuseOptions& options, Executor& executor, Progress& progress);

}  // namespace relief::pipeline
