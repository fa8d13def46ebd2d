#pragma once
// manifest.json: the global description of one dataset (see docs/store-format.md).
#include <optional>
#include <string>
#include <vector>

#include "relief/base/result.h"
#include "relief/geo/tile_key.h"
#include "relief/tiles/codec.h"
#include "relief/tiles/raster.h"

namespace relief::tiles {

// 2: level indexes carry each tile's geometric error (level index version 2).
inline constexpr int kStoreFormatVersion = 2;

// The one-line error for a file of a store written before geometric errors
// (format 1): names the file and says how to upgrade the store.
std::string predates_geometric_errors(const std::string& file);
// The format version a relief store manifest declares; nullopt for anything else.
std::optional<int> manifest_format_version(const std::string& text);

enum class DatasetKind { Elevation, Imagery, Sar };
std::string_view to_string(DatasetKind k);
Result<DatasetKind> dataset_kind_from_string(std::string_view s);

struct SourceInfo {
  std::string path;
  std::string crs;  // authority code when known ("EPSG:32618"), else WKT
  int width = 0, height = 0, bands = 0;
  std::string data_type;  // as GDAL names it
};

struct Manifest {
  int format_version = kStoreFormatVersion;
  DatasetKind kind = DatasetKind::Elevation;
  SampleType sample_type = SampleType::Float32;
  int bands = 1;
  std::string units;  // "m" for elevation, "amplitude" for SAR, "" for imagery
  int tile_log2_height = 8;
  int border = 9;
  int min_level = 0, max_level = 0;
  geo::GeoBox extent{-180, -90, 180, 90};  // of the source data, degrees
  SampleStats stats;                       // over all valid samples of the finest level
  CodecOptions codec;
  std::vector<SourceInfo> sources;
  std::string created_by;
  // Tiles of different depths (elevation layers fused at draw time,
  // pipeline/fused_elevation.h): where a tile has no child, its data goes on
  // below it (drawn from it), instead of there being no data.
  bool sparse_depth = false;

  std::string nodata_description() const;
  std::string to_json() const;
  // Parses and checks the manifest (see check_consistency); errors start with `name`.
  static Result<Manifest> from_json(const std::string& text, const std::string& name);
};

// Whether the fields agree with each other: kind and sample type (imagery is
// uint8 RGBA, elevation and SAR float32), bands, codec, extent, statistics.
Status check_consistency(const Manifest& m, const std::string& name);

}  // namespace relief::tiles
