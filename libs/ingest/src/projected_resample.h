#pragma once
// relief's own warp kernel for single-band inputs in any CRS (UTM, Lambert,
// rotated grids, or WGS84 grids the direct path leaves out): the path GDAL's
// warper took once per tile, without its per-tile setup (transformer, masks,
// chunking, a MEM dataset).
//
// Source coordinates come from GDAL's own transformer, built as gdalwarp
// builds it (the general image-to-image transformer wrapped in the
// approximate transformer with the same error threshold) and called for
// whole destination rows as GDAL's kernel calls it, so every sample is taken
// at the source position GDAL would use. The kernel is GDAL's bilinear: the
// 2 x 2 formula when the resampling scale is at least 0.95, otherwise the
// widened filter GDAL uses when downsampling (radius ceil(1 / scale), weights
// of the triangle function stretched by 1 / scale), with GDAL's handling of
// invalid samples and edges. Results equal GDAL's warper's to a bit or two
// (coordinates are taken relative to the raster, not to GDAL's window).
#include <cstdint>
#include <memory>
#include <optional>

#include "gdal_env.h"
#include "relief/base/result.h"
#include "relief/geo/tile_grid.h"
#include "relief/tiles/raster.h"

namespace relief::ingest {

class ProjectedResampler {
 public:
  // nullopt when `ds` does not qualify: not one band, no geotransform or CRS,
  // or GDAL cannot build the transformer. `ds` must outlive the resampler and
  // be used by one thread at a time. error_threshold as gdalwarp -et.
  static std::optional<ProjectedResampler> create(GDALDatasetH ds, double error_threshold);

  // Paints the valid bilinear samples of the source over `tile` (the interior
  // of `key`), leaving the others untouched, as GDAL mosaics sources. scale:
  // GDAL's XSCALE = YSCALE (1 when upsampling). False, with `tile` untouched,
  // when the tile needs more source than kMaxWindowSamples (a tile far
  // coarser than the source, where GDAL's warper works in chunks instead).
  Result<bool> resample(const geo::TileGrid& grid, const geo::TileKey& key, double scale,
                        tiles::Raster& tile);
  static constexpr int64_t kMaxWindowSamples = int64_t{1} << 20;  // 8 MiB of doubles

 private:
  struct TransformerDeleter {
    void operator()(void* t) const;
  };
  GDALDatasetH ds_ = nullptr;
  Dataset dst_;  // a 1 x 1 stand-in for the tile: its CRS and geotransform
  std::unique_ptr<void, TransformerDeleter> exact_, approx_;
  int width_ = 0, height_ = 0;
  bool has_nodata_ = false;
  double nodata_ = 0;
};

}  // namespace relief::ingest
