#pragma once
// Coarser pyramid levels: each parent sample is the nodata-aware mean of the
// 2 x 2 child samples whose cells it covers (cell-centred registration makes
// this exact, see geo/tile_grid.h).
#include <array>

#include "relief/tiles/raster.h"

namespace relief::ingest {

// children[cy * 2 + cx] is child (cx, cy) of the parent, interior only, or
// nullptr where the child is empty. Returns the parent's interior.
tiles::Raster downsample(const std::array<const tiles::Raster*, 4>& children, int width, int height,
                         tiles::SampleType type);

// Copies the 3 x 3 neighbourhood of interiors into one bordered tile.
// neighbours[(dy + 1) * 3 + (dx + 1)] is the interior of neighbour (dx, dy), or
// nullptr (empty or beyond a pole).
tiles::Raster assemble_bordered(const std::array<const tiles::Raster*, 9>& neighbours, int width,
                                int height, int border, tiles::SampleType type);

}  // namespace relief::ingest
