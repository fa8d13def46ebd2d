#pragma once
// Bordered tiles from the interiors of their neighbours: the overlap border of
// a tile is the neighbouring tiles' interior samples (seed 003 §1.2.3), so a
// tile's border and its neighbour's interior can never disagree.
#include <array>
#include <span>

#include "relief/tiles/raster.h"

namespace relief::tiles {

// Copies the 3 x 3 neighbourhood of interiors into one bordered tile of
// (width + 2 border) x (height + 2 border) samples; border <= width, height.
// neighbours[(dy + 1) * 3 + (dx + 1)] is the interior of neighbour (dx, dy), or
// nullptr (empty or beyond a pole): those samples are nodata.
Raster assemble_bordered(const std::array<const Raster*, 9>& neighbours, int width, int height,
                         int border, SampleType type);

// Statistics of the union of disjoint sample sets, combined in the order
// given (so the result does not depend on which thread finished first).
// `channels` is 3 for RGBA imagery (statistics over the colour channels).
SampleStats combine_stats(std::span<const SampleStats> parts, int channels);

}  // namespace relief::tiles
