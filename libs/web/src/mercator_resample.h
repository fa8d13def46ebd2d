#pragma once
// A Web Mercator tile's pixels resampled from a store's quadtree levels
// (docs/web.md, "Resampling"): each row of pixels reads the level that
// source_level chooses, bilinearly over cell-centred samples.
#include <vector>

#include "relief/base/result.h"
#include "relief/web/web_mercator.h"
#include "sample_block.h"

namespace relief::web {

struct ResampleSource {
  int log2_tile_height = 8;  // the store grid's: a tile is 2^(k+1) x 2^k samples
  int min_level = 0, max_level = 0;
  // Samples whose cells lie wholly outside this box are not read (nodata):
  // a tile of zoom 0 would otherwise read a whole level of the world.
  geo::GeoBox data;
};

// The store level a row of pixels at latitude `lat` reads; see raster_tiles.h.
int source_level(const ResampleSource& source, int z, int tile_size, double lat);

// Heights of the pixel centres, row-major from the north-west, NaN where no
// sample around a pixel has data. Where only some have, their weights are
// renormalised: the data's edge stays where the data is, not pulled to 0.
Result<std::vector<double>> resample_heights(const SampleBlocks& blocks,
                                             const ResampleSource& source, const XyzKey& key,
                                             int tile_size);

// Colours of the pixel centres, interpolated with premultiplied alpha (a
// transparent sample adds no colour, so edges of the data do not darken),
// transparent where no sample around a pixel has data.
Result<std::vector<Rgba>> resample_pixels(const PixelBlocks& blocks, const ResampleSource& source,
                                          const XyzKey& key, int tile_size);

}  // namespace relief::web
