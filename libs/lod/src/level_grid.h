#pragma once
// What the tree of a finished selection holds at each quad position, in one
// byte per position of a dense grid per level over the box of that level's
// quads: a leaf, a split quad, or nothing. Classifying a quad's eight
// neighbours then reads bytes beside each other instead of probing a hash map
// eight times (each probe a likely cache miss). A level whose quads spread
// over too large a box (across the antimeridian, say) is not gridded: the
// caller falls back to the map.
#include <algorithm>
#include <cstdint>
#include <vector>

#include "relief/geo/tile_key.h"

namespace relief::lod {

class LevelGrid {
 public:
  enum class Cell : uint8_t { kNone, kLeaf, kSplit, kUnknown };

  // `for_each(f)` calls f(key, split) for every quad of the tree.
  template <class ForEach>
  void build(ForEach for_each) {
    for (Level& l : levels_) l = Level{};
    for_each([&](const geo::TileKey& k, bool) { level(k.level).extend(k.x, k.y); });
    for (Level& l : levels_) l.allocate();
    for_each([&](const geo::TileKey& k, bool split) {
      if (uint8_t* c = level(k.level).cell(k.x, k.y)) {
        *c = static_cast<uint8_t>(split ? Cell::kSplit : Cell::kLeaf);
      }
    });
  }

  Cell at(const geo::TileKey& k) const {
    if (k.level < 0 || static_cast<size_t>(k.level) >= levels_.size()) return Cell::kNone;
    const Level& l = levels_[static_cast<size_t>(k.level)];
    if (!l.gridded) return l.count ? Cell::kUnknown : Cell::kNone;
    if (k.x < l.x0 || k.x > l.x1 || k.y < l.y0 || k.y > l.y1) return Cell::kNone;
    return static_cast<Cell>(l.cells[(k.y - l.y0) * l.width() + (k.x - l.x0)]);
  }

 private:
  // Larger boxes than this many cells per quad are left to the map.
  static constexpr uint64_t kMaxCellsPerQuad = 64;

  struct Level {
    uint32_t x0 = UINT32_MAX, y0 = UINT32_MAX, x1 = 0, y1 = 0;
    uint64_t count = 0;
    bool gridded = false;
    std::vector<uint8_t> cells;
    uint64_t width() const { return uint64_t{x1} - x0 + 1; }
    void extend(uint32_t x, uint32_t y) {
      x0 = std::min(x0, x), x1 = std::max(x1, x), y0 = std::min(y0, y), y1 = std::max(y1, y);
      ++count;
    }
    void allocate() {
      if (!count) return;
      const uint64_t area = width() * (uint64_t{y1} - y0 + 1);
      gridded = area <= count * kMaxCellsPerQuad;
      if (gridded) cells.assign(area, static_cast<uint8_t>(Cell::kNone));
    }
    uint8_t* cell(uint32_t x, uint32_t y) {
      return gridded ? &cells[(y - y0) * width() + (x - x0)] : nullptr;
    }
  };
  Level& level(int l) {
    if (static_cast<size_t>(l) >= levels_.size()) levels_.resize(static_cast<size_t>(l) + 1);
    return levels_[static_cast<size_t>(l)];
  }

  std::vector<Level> levels_;
};

}  // namespace relief::lod
