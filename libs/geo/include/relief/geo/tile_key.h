#pragma once
// Addresses in the WGS84 geographic quadtree (seed 003 §1.2.2).
//
// Level 0 is a single quad covering longitude -180..180 and latitude -90..90,
// twice as wide in degrees as high. Level l has 2^l x 2^l quads; x grows east
// from -180, y grows south from +90 (row order of a north-up raster). Columns
// wrap across the antimeridian; rows end at the poles.
#include <compare>
#include <cstdint>
#include <optional>
#include <string>

namespace relief::geo {

inline constexpr int kMaxLevel = 30;

struct GeoBox {
  double west = 0, south = 0, east = 0, north = 0;  // degrees
  double width() const { return east - west; }
  double height() const { return north - south; }
  bool intersects(const GeoBox& o) const {
    return west < o.east && o.west < east && south < o.north && o.south < north;
  }
};

struct TileKey {
  int level = 0;
  uint32_t x = 0;
  uint32_t y = 0;

  auto operator<=>(const TileKey&) const = default;

  static uint32_t tiles_per_side(int level) { return 1u << level; }
  bool valid() const;

  GeoBox bounds() const;
  std::optional<TileKey> parent() const;
  TileKey child(int cx, int cy) const;  // cx, cy in {0, 1}
  // Neighbour dx, dy quads away: x wraps around the antimeridian, y stops at the poles.
  std::optional<TileKey> neighbour(int dx, int dy) const;

  // Morton (Z-order) index: bits of x and y interleaved, x in the even bits.
  uint64_t morton() const;
  static TileKey from_morton(int level, uint64_t morton);
  // Quadkey string: one base-4 digit per level (digit = 2*ybit + xbit), "" at level 0.
  std::string quadkey() const;

  std::string to_string() const;  // "level/x/y"
};

// Inline: the quad selection calls it in its innermost loops. n is a power
// of two: the mask wraps columns on either side (a modulo that is never
// negative) without the two 64-bit divisions of `%`.
inline std::optional<TileKey> TileKey::neighbour(int dx, int dy) const {
  const int64_t n = tiles_per_side(level);
  const int64_t ny = static_cast<int64_t>(y) + dy;
  if (ny < 0 || ny >= n) return std::nullopt;
  const int64_t nx = (static_cast<int64_t>(x) + dx) & (n - 1);
  return TileKey{level, static_cast<uint32_t>(nx), static_cast<uint32_t>(ny)};
}

// A cheap, well-mixed hash (packed fields, murmur finaliser): level-of-detail
// selection probes maps of quads hundreds of thousands of times a second.
struct TileKeyHash {
  size_t operator()(const TileKey& k) const {
    uint64_t h = (static_cast<uint64_t>(k.level) << 58) ^ (static_cast<uint64_t>(k.x) << 29) ^ k.y;
    h ^= h >> 33;
    h *= 0xff51afd7ed558ccdULL;
    h ^= h >> 33;
    return static_cast<size_t>(h);
  }
};

}  // namespace relief::geo
