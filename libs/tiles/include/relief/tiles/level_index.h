#pragma once
// Per-level metadata index: which tiles exist and their value bounds, small
// enough to fetch before any tile so LOD selection can bound unloaded quads
// (the role of Comet's tile-corner elevation buffer, seed 000 §3.2.3).
//
// Binary layout (little-endian): magic "RELIEFI\0", u16 version, u16 level,
// u32 x0, y0, columns, rows (bounding box of present tiles), u64 count, the
// presence bitmap of columns*rows bits (row-major, LSB first), then `count`
// records {f32 min, f32 max, u32 valid samples, u32 file bytes, f32 geometric
// error} in bitmap order, then u32 CRC-32 of everything before it. min/max are
// rounded outwards, the error upwards. Version 1 (no error) is refused with the
// advice to run `relief upgrade`.
#include <cstdint>
#include <span>
#include <string>
#include <vector>

#include "relief/base/result.h"
#include "relief/geo/tile_key.h"

namespace relief::tiles {

struct IndexEntry {
  geo::TileKey key;
  float min = 0, max = 0;
  uint32_t valid_count = 0;
  uint32_t file_bytes = 0;
  // Geometric error, metres: the largest vertical distance between this
  // level's full mesh of the tile and the finest data below it (see
  // docs/store-format.md). 0 at the finest level.
  float error = 0;
};

inline constexpr uint16_t kLevelIndexVersion = 2;
inline constexpr size_t kLevelIndexRecordSize = 20;

class LevelIndex {
 public:
  explicit LevelIndex(int level = 0) : level_(level) {}
  int level() const { return level_; }

  void add(const IndexEntry& e);                         // keys must be unique
  void set_error(const geo::TileKey& key, float error);  // the key must be present
  const IndexEntry* find(const geo::TileKey& key) const;
  // Entries sorted by (y, x).
  const std::vector<IndexEntry>& entries() const;
  size_t size() const { return entries_.size(); }
  uint64_t total_bytes() const;

  std::vector<std::byte> serialize() const;
  static Result<LevelIndex> parse(std::span<const std::byte> bytes, const std::string& name);
  // Also reads version 1 (errors 0): for `relief upgrade` only.
  static Result<LevelIndex> parse_for_upgrade(std::span<const std::byte> bytes,
                                              const std::string& name);

 private:
  static Result<LevelIndex> parse_any(std::span<const std::byte> bytes, const std::string& name,
                                      bool accept_version1);
  void sort() const;
  int level_;
  mutable std::vector<IndexEntry> entries_;
  mutable bool sorted_ = true;
};

}  // namespace relief::tiles
