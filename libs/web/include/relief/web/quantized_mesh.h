#pragma once
// Cesium's quantized-mesh-1.0 terrain format (docs/web.md): one tile's mesh
// as 16-bit u, v and height per vertex over the tile's rectangle, the
// triangles, the vertices on each edge (from which the client builds skirts)
// and extensions (oct-encoded vertex normals, availability metadata).
#include <cstddef>
#include <cstdint>
#include <optional>
#include <string>
#include <vector>

#include "relief/geo/ellipsoid.h"
#include "relief/geo/tile_key.h"

namespace relief::web {

inline constexpr int kQuantizedMax = 32767;  // u, v and height run over 0..32767

struct QuantizedMeshInput {
  geo::GeoBox rect;           // degrees
  std::vector<uint16_t> u;    // 0 = west edge, 32767 = east edge
  std::vector<uint16_t> v;    // 0 = south edge, 32767 = north edge
  std::vector<float> height;  // metres above the ellipsoid, per vertex
  // Three indices per triangle, counter-clockwise with u east and v north;
  // vertices numbered in order of first use (high-water-mark coding needs it).
  std::vector<uint32_t> triangles;
  std::vector<geo::Ecef> normals;            // unit ECEF normals per vertex; empty = none
  std::optional<std::string> metadata_json;  // the `metadata` extension
};

// The tile's bytes, uncompressed. The header's heights, centre, bounding
// sphere and horizon occlusion point describe the vertices as a client
// decodes them.
std::vector<std::byte> encode_quantized_mesh(const QuantizedMeshInput& in);

// The horizon occlusion point in ellipsoid-scaled space (x/a, y/a, z/b) of
// these ECEF points seen along `direction` (Cesium's EllipsoidalOccluder):
// if the point is below the horizon, so is every point. nullopt when no
// point on that ray works (a tile reaching 90 degrees from it).
std::optional<geo::Ecef> horizon_occlusion_point(const std::vector<geo::Ecef>& points,
                                                 const geo::Ecef& direction);

// Cesium's octahedral unit-vector encoding in two bytes (AttributeCompression.octEncode).
void oct_encode(const geo::Ecef& unit, uint8_t& x, uint8_t& y);

// The geometric error CesiumJS assumes for a terrain tile of `level` in the
// geographic scheme, metres: a * 2 pi * 0.25 / (65 * 2) / 2^level.
double cesium_level_error(int level);

// gzip (RFC 1952) at zlib level 6 with no name and no time: the same input
// gives the same bytes.
std::vector<std::byte> gzip(const std::vector<std::byte>& bytes);

}  // namespace relief::web
