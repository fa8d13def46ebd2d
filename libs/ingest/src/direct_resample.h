#pragma once
// A fast path for the most common elevation input: rasters already on a
// north-up WGS84 longitude/latitude grid (SRTM, Copernicus DEM, most global
// DEMs). Reprojection is then an axis-aligned affine map, so the source pixel
// column depends only on the destination column and the row only on the row;
// bilinear weights are computed once per column and per row instead of per
// sample. The arithmetic follows GDAL's warp kernel exactly (only points inside
// the raster whose own source pixel is valid; weights of valid neighbours
// renormalised, invalid below a total weight of 1e-5; the same accumulation
// order), so the result equals GDAL's warper's to the last bit or two.
#include <functional>
#include <memory>
#include <mutex>
#include <optional>
#include <vector>

#include "gdal_env.h"
#include "relief/base/result.h"
#include "relief/geo/tile_grid.h"
#include "relief/tiles/raster.h"

namespace relief::ingest {

class DirectResampler {
 public:
  // nullopt when `ds` does not qualify: not one band, not north-up, not WGS84
  // geographic with longitude first, outside -180..180, or coarser than the
  // destination (GDAL then widens its kernel, which this path does not do).
  static std::optional<DirectResampler> create(GDALDatasetH ds, double destination_spacing);

  // Paints the valid bilinear samples of the source over `tile` (the interior
  // of `key`), leaving the others untouched, as GDAL mosaics sources. With
  // `cover` (the first source painted) the others are set to nodata: `tile`
  // may then start uninitialised, and its samples are written once.
  Status resample(const geo::TileGrid& grid, const geo::TileKey& key, tiles::Raster& tile,
                  bool cover = false) const;

  // Source reads take this lock (for a dataset shared between threads).
  void serialise_reads(std::mutex* m) { read_mutex_ = m; }

 private:
  GDALDatasetH ds_ = nullptr;
  std::mutex* read_mutex_ = nullptr;
  double gt_[6] = {};
  int width_ = 0, height_ = 0;
  bool has_nodata_ = false;
  double nodata_ = 0;
  bool exact_in_float_ = false;  // a float holds every value of the band's type
};

// Direct resamplers shared by every worker of a build: one GDAL dataset per
// mosaic group, so each source block is read (an .hgt.zip inflated) once per
// build instead of once per worker, in GDAL's block cache. Reads of a group
// are serialised; the resampling runs in parallel. Thread-safe.
class SharedDirectSources {
 public:
  explicit SharedDirectSources(size_t groups);
  // Group g's resampler, its dataset opened by `open` on first use; nullptr
  // when the group does not qualify or cannot be opened.
  const DirectResampler* get(size_t g, double destination_spacing,
                             const std::function<Result<Dataset>()>& open);

 private:
  struct Slot {
    std::once_flag once;
    Dataset ds;
    std::optional<DirectResampler> resampler;
    std::mutex reads;
  };
  std::vector<std::unique_ptr<Slot>> slots_;
};

}  // namespace relief::ingest
