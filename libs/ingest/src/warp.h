#pragma once
// Resamples the sources onto the interior samples of one finest-level tile,
// through GDAL's warper. Not thread-safe: each worker owns a TileWarper, which
// opens its own GDAL datasets (GDAL datasets must not be shared by threads).
#include <map>
#include <string>
#include <vector>

#include "gdal_env.h"
#include "relief/base/result.h"
#include "relief/geo/tile_grid.h"
#include "relief/tiles/manifest.h"
#include "relief/tiles/raster.h"
#include "source.h"

namespace relief::ingest {

class TileWarper {
 public:
  TileWarper(const std::vector<Source>& sources, tiles::DatasetKind kind, geo::TileGrid grid);

  // The tile's interior (no border). A tile no source covers comes back empty
  // (all nodata), which callers check with stats().valid_count.
  Result<tiles::Raster> warp(const geo::TileKey& key);
  // Indices of the sources whose footprint meets the tile (antimeridian-aware).
  std::vector<size_t> sources_for(const geo::TileKey& key) const;

 private:
  Result<GDALDatasetH> source_handle(size_t i);
  const std::vector<Source>& sources_;
  tiles::DatasetKind kind_;
  geo::TileGrid grid_;
  std::map<size_t, Dataset> open_;
};

}  // namespace relief::ingest
