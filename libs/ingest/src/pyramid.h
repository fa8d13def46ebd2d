#pragma once
// Coarser pyramid levels: each parent sample is the nodata-aware mean of the
// 2 x 2 child samples whose cells it covers (cell-centred registration makes
// this exact, see geo/tile_grid.h).
#include <array>

#include "relief/tiles/assemble.h"
#include "relief/tiles/raster.h"

namespace relief::ingest {

// children[cy * 2 + cx] is child (cx, cy) of the parent, interior only, or
// nullptr where the child is empty. Returns the parent's interior.
tiles::Raster downsample(const std::array<const tiles::Raster*, 4>& children, int width, int height,
                         tiles::SampleType type);

}  // namespace relief::ingest
