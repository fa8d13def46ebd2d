#pragma once
// Per-tile fusion of several stores' tiles, shared by `relief fuse` (offline,
// fuse_stores.h) and the draw-time fusion of elevation layers
// (fused_elevation.h), so both give the same samples.
#include <string>
#include <vector>

#include "relief/base/result.h"
#include "relief/geo/tile_grid.h"
#include "relief/geo/tile_key.h"
#include "relief/tiles/raster.h"

namespace relief::pipeline {

enum class FuseMode {
  Blend,  // weighted mean of the valid inputs
  First,  // the first valid input in the order given (void filling)
};

// The weights of `inputs` fused inputs as `relief fuse --weights` and the
// draw-time fusion take them: one per input (an error names `inputs_name`
// when the count differs), each > 0 and finite; empty means all 1. Scaled so
// the largest is 1: only the ratios matter, and weighted sums of float
// samples then cannot overflow (1e308 + 1e308 would be inf, and inf / inf NaN).
Result<std::vector<double>> fuse_weights(std::vector<double> weights, size_t inputs,
                                         const std::string& inputs_name);

// Float samples of `out` (the size of every non-null input): the weighted
// mean (or the first valid, in input order) of the inputs' valid samples;
// NaN where none is valid. Null inputs have no tile there.
void fuse_float(const std::vector<const tiles::Raster*>& in, const std::vector<double>& weights,
                FuseMode mode, tiles::Raster& out);

// Tile `target`, at a level finer than the input's finest, bilinearly
// upsampled from the input's tile `ancestor` (bordered rasters, both): an
// input built to a coarser level still fills the levels below its own. A
// sample is valid where the nearest ancestor sample is; nodata neighbours are
// left out of the weights.
tiles::Raster upsample(const tiles::Raster& ancestor, const geo::TileKey& a,
                       const geo::TileKey& target, const geo::TileGrid& grid);

}  // namespace relief::pipeline
