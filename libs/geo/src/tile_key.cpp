#include "relief/geo/tile_key.h"

#include <cassert>

#include <fmt/format.h>

namespace relief::geo {

bool TileKey::valid() const {
  return level >= 0 && level <= kMaxLevel && x < tiles_per_side(level) && y < tiles_per_side(level);
}

GeoBox TileKey::bounds() const {
  const double n = tiles_per_side(level);
  const double w = 360.0 / n, h = 180.0 / n;
  return {-180.0 + x * w, 90.0 - (y + 1) * h, -180.0 + (x + 1) * w, 90.0 - y * h};
}

std::optional<TileKey> TileKey::parent() const {
  if (level == 0) return std::nullopt;
  return TileKey{level - 1, x >> 1, y >> 1};
}

TileKey TileKey::child(int cx, int cy) const {
  assert(level < kMaxLevel && (cx == 0 || cx == 1) && (cy == 0 || cy == 1));
  return {level + 1, x * 2 + static_cast<uint32_t>(cx), y * 2 + static_cast<uint32_t>(cy)};
}

namespace {
uint64_t spread_bits(uint32_t v) {
  uint64_t x = v;
  x = (x | (x << 16)) & 0x0000FFFF0000FFFFull;
  x = (x | (x << 8)) & 0x00FF00FF00FF00FFull;
  x = (x | (x << 4)) & 0x0F0F0F0F0F0F0F0Full;
  x = (x | (x << 2)) & 0x3333333333333333ull;
  x = (x | (x << 1)) & 0x5555555555555555ull;
  return x;
}
uint32_t compact_bits(uint64_t x) {
  x &= 0x5555555555555555ull;
  x = (x | (x >> 1)) & 0x3333333333333333ull;
  x = (x | (x >> 2)) & 0x0F0F0F0F0F0F0F0Full;
  x = (x | (x >> 4)) & 0x00FF00FF00FF00FFull;
  x = (x | (x >> 8)) & 0x0000FFFF0000FFFFull;
  x = (x | (x >> 16)) & 0x00000000FFFFFFFFull;
  return static_cast<uint32_t>(x);
}
}  // namespace

uint64_t TileKey::morton() const {
  return spread_bits(x) | (spread_bits(y) << 1);
}

TileKey TileKey::from_morton(int level, uint64_t m) {
  return {level, compact_bits(m), compact_bits(m >> 1)};
}

std::string TileKey::quadkey() const {
  std::string key;
  for (int i = level - 1; i >= 0; --i) {
    const int digit = static_cast<int>(((x >> i) & 1u) | (((y >> i) & 1u) << 1));
    key.push_back(static_cast<char>('0' + digit));
  }
  return key;
}

std::string TileKey::to_string() const {
  return fmt::format("{}/{}/{}", level, x, y);
}

}  // namespace relief::geo
