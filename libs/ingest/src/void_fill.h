#pragma once
// Void filling for elevation sources (`relief build --fill-voids`).
//
// A void is a hole in the data such as SRTM's radar shadows: a nodata region
// inside the raster, or one on its edge holding at most 1 % of its samples
// (a void cut by a tile boundary). Larger nodata regions on the edge (a
// collar, the area outside a scene) are not voids and stay nodata. Voids are
// filled by pull-push interpolation: a pyramid of nodata-aware means of the
// source, then every void sample takes the bilinear interpolation of the
// next coarser level, from the coarsest down, so a fill blends smoothly into
// the data around it. Valid samples are never changed.
#include <cstdint>
#include <filesystem>
#include <optional>
#include <vector>

#include "relief/base/result.h"

namespace relief::ingest {

// Fills the voids of `values` (width x height, row-major, nodata as NaN) in
// place; returns how many samples were filled.
uint64_t fill_voids(std::vector<float>& values, int width, int height);

struct FilledSource {
  std::filesystem::path path;  // the filled copy (same georeferencing and type)
  uint64_t filled = 0;         // void samples filled
};

// Reads the elevation raster `path` (band 1) into memory, fills its voids and
// writes a GeoTIFF copy to `copy`. nullopt when the source has no void, unless
// `always_copy`: a source mosaicked with filled ones is copied unchanged, so
// every file of the mosaic has the same format (GDAL's VRT builder leaves out
// a file whose data type or colour interpretation differs from the first).
Result<std::optional<FilledSource>> fill_source_voids(const std::string& path,
                                                      const std::filesystem::path& copy,
                                                      bool always_copy = false);

}  // namespace relief::ingest
