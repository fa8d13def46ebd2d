#pragma once
// Validation and description of build inputs: what each file is, where it lies
// in WGS84 longitude/latitude and how fine its samples are.
#include <optional>
#include <string>
#include <vector>

#include "relief/base/result.h"
#include "relief/geo/tile_key.h"
#include "relief/tiles/manifest.h"

namespace relief::ingest {

struct Source {
  std::string path;
  std::string crs_wkt;       // as given, or from --src-crs
  std::string crs_name;      // authority code when known, else WKT
  bool crs_assumed = false;  // none given: WGS84 taken from a geographic extent
  int width = 0, height = 0;
  int colour_bands = 0;  // bands carried into the store (alpha excluded)
  bool has_alpha = false;
  std::string data_type;
  int sample_bytes = 0;  // of data_type
  int block_height = 1;  // rows of the blocks GDAL reads and caches
  // What GDAL's VRT builder requires to be equal between mosaicked files
  // (data type, colour interpretation and table per band); it skips a file
  // that differs, so only sources with equal keys share a mosaic.
  std::string mosaic_key;
  bool north_up = true;    // plain geotransform: no rotation terms, no GCPs
  geo::GeoBox box;         // lon/lat extent; east may exceed 180 if it crosses the antimeridian
  double spacing_deg = 0;  // sample spacing in degrees after reprojection
  std::string filled;      // a copy with its voids filled (--fill-voids), if any
  // A global grid in longitudes 0..360: a VRT (XML text, which GDAL opens as
  // a dataset) with its columns rotated into -180..180; empty otherwise.
  std::string wrapped;

  // The raster as it lies on the globe (void filling reads this one).
  const std::string& read_path() const { return wrapped.empty() ? path : wrapped; }
  // The file the warper reads.
  const std::string& open_path() const { return filled.empty() ? read_path() : filled; }
};

// Opens `path` and checks that it can go into a dataset of `kind`.
Result<Source> describe_source(const std::string& path, tiles::DatasetKind kind,
                               const std::optional<std::string>& src_crs);
// Checks that the sources can be mosaicked into one dataset.
Status check_compatible(const std::vector<Source>& sources);

tiles::SourceInfo to_source_info(const Source& s);

}  // namespace relief::ingest
