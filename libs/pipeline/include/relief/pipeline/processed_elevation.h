#pragma once
// Elevation processed at draw time (issue 14): an elevation store (one store,
// or layers fused at draw time: fused_elevation.h) presented as one store
// whose tiles go through an operator chain when read, on the reading thread
// (the tile loader's threads when drawing). Each tile is processed from its
// own overlap border by the CPU reference of the texture layers' chains
// (gpuprocess::run_chain_cpu) and keeps a two-sample border (what the
// renderer's hillshade reads beyond a tile's edge): the presented store's
// border is 2, and a chain's margins may use the rest of the input's. Lenses: inside a circle on
// the ellipsoid a sample takes the lens chain's value, outside the global chain's, decided per
// sample by its own position, so the processed heights are one function of
// position and tiles sharing a side agree there bit for bit.
//
// The guarantee: the level indexes are built when the store is opened, each
// tile's bounds and the exact geometric errors of the PROCESSED pyramid
// computed by the same code as `relief build` (tiles/geometric_error.h) over
// the processed tiles, as for fused layers. Selection and edge-mark
// refinement see an ordinary store. Opening processes every tile once
// (docs/rendering.md, "Elevation operators and lenses at draw time").
#include <string>
#include <vector>

#include "relief/base/parallel.h"
#include "relief/base/result.h"
#include "relief/gpuprocess/chain.h"
#include "relief/tiles/store.h"

namespace relief::pipeline {

// A circle on the ellipsoid (centre in degrees, radius in metres measured as
// the texture layers' lenses measure it: on the tangent plane at the centre)
// with its own chain, parameters for the store's finest level.
struct ElevationLens {
  double lon = 0, lat = 0, radius_m = 0;
  gpuprocess::OperatorChain chain;
};

struct ElevationProcessing {
  gpuprocess::OperatorChain chain;    // outside every lens; parameters for the finest level
  std::vector<ElevationLens> lenses;  // where several hold a sample, the last given wins
  bool empty() const { return chain.steps.empty() && lenses.empty(); }
};

// The operators valid for heights: those of the catalogue not marked SAR-only
// (mean, gauss, median). Speckle filters, amplitude/intensity/dB conversions
// and the dynamic-range mappings are refused naming the operator, as a chain
// wider than the store's border less the 2 samples kept (7 of the default 9,
// at the finest level: coarser levels have smaller masks) or a lens radius
// <= 0.
// `name` (the store) starts every message.
Status check_elevation_processing(const ElevationProcessing& processing,
                                  const tiles::Manifest& manifest, const std::string& name);

// The store of `store`'s tiles processed (checked as above; a store of
// sparse depth, layers of different depths, is refused). Opening processes
// every tile once on `executor` for the indexes.
Result<tiles::Store> process_elevation(tiles::Store store, const std::string& name,
                                       ElevationProcessing processing, Executor& executor);

// Metres from (lon0, lat0) to (lon, lat) on the tangent plane at (lon0,
// lat0): what a lens's radius is compared with (as view::lens_distance_m).
double lens_distance_m(double lon0, double lat0, double lon, double lat);

}  // namespace relief::pipeline
