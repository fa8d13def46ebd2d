#pragma once
// Resamples the sources onto the interior samples of one finest-level tile,
// through GDAL's warper. Not thread-safe: each worker owns a TileWarper, which
// opens its own GDAL datasets (GDAL datasets must not be shared by threads),
// except for the direct path's, shared through SharedDirectSources.
//
// Sources that share a CRS and have north-up geotransforms are first mosaicked
// on their native grid (a VRT, later inputs on top), so bilinear interpolation
// across the seam between two inputs uses samples of both; warping them one by
// one would let each input's edge half-pixel overwrite its neighbour's data.
#include <string>
#include <vector>

#include <optional>

#include "direct_resample.h"
#include "gdal_env.h"
#include "projected_resample.h"
#include "relief/base/result.h"
#include "relief/geo/tile_grid.h"
#include "relief/tiles/manifest.h"
#include "relief/tiles/raster.h"
#include "source.h"

namespace relief::ingest {

struct MosaicGroup {
  std::vector<size_t> members;  // indices into the source list, in input order
  geo::GeoBox box;              // union of the members' footprints
};
// Groups sources for mosaicking, keeping input order between groups.
std::vector<MosaicGroup> group_sources(const std::vector<Source>& sources);

class TileWarper {
 public:
  // error_threshold: largest error in source pixels of GDAL's approximate
  // transformer (0 = transform every sample exactly), as gdalwarp -et.
  // direct: use DirectResampler where a group qualifies (same result, faster).
  // shared: the build's shared direct resamplers (nullptr: this warper's own).
  TileWarper(const std::vector<Source>& sources, const std::vector<MosaicGroup>& groups,
             tiles::DatasetKind kind, geo::TileGrid grid, double error_threshold, bool direct,
             SharedDirectSources* shared = nullptr);

  // The tile's interior (no border). A tile no source covers comes back empty
  // (all nodata), which callers check with stats().valid_count.
  Result<tiles::Raster> warp(const geo::TileKey& key);

 private:
  std::vector<size_t> groups_for(const geo::TileKey& key) const;
  Result<GDALDatasetH> group_handle(size_t g);
  Result<Dataset> open_group(size_t g) const;
  // The direct resampler of group g, if it qualifies (decided on first use).
  const DirectResampler* direct_for(size_t g, int level);
  Result<tiles::Raster> warp_direct(const geo::TileKey& key, const std::vector<size_t>& groups);
  // relief's own kernel for group g (any CRS), if it qualifies (decided on first use).
  ProjectedResampler* projected_for(size_t g);
  // The resampling scale GDAL is given for this tile (1 when upsampling).
  double scale_for(const geo::TileKey& key, const std::vector<size_t>& groups) const;

  const std::vector<Source>& sources_;
  const std::vector<MosaicGroup>& groups_;
  tiles::DatasetKind kind_;
  geo::TileGrid grid_;
  double error_threshold_;
  bool direct_;
  SharedDirectSources* shared_;
  std::vector<Dataset> open_;  // per group, opened on first use
  std::vector<std::optional<std::optional<DirectResampler>>> direct_resamplers_;  // per group
  std::vector<std::optional<std::optional<ProjectedResampler>>> projected_;       // per group
};

}  // namespace relief::ingest
