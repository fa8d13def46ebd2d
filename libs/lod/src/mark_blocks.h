#pragma once
// The edge marks (one byte per grid point, 0 = undecided) of every quad of
// one refinement, stored in blocks of 16 x 16 grid points allocated, zeroed,
// on the first write. A frame decides a small part of each quad's grid (a
// distant quad a few dozen marks of its 2^(2k+1) points): clearing whole
// grids, about 0.5 MB a quad of 512 x 256 samples, took more time than
// deciding the marks. Addresses stay valid until reset().
#include <algorithm>
#include <cstdint>
#include <memory>
#include <vector>

#include "edge_marks.h"

namespace relief::lod {

class MarkBlocks {
 public:
  // Room for `quads` quads of `grid`, every mark undecided.
  void reset(const MarkGrid& grid, size_t quads) {
    columns_ = (grid.columns() + kSide - 1) / kSide;
    per_quad_ = static_cast<size_t>(columns_) * ((grid.rows() + kSide - 1) / kSide);
    table_.assign(quads * per_quad_, kNone);
    used_ = 0;
  }

  uint8_t get(int q, GridPoint p) const {
    const uint32_t b = table_[slot(q, p)];
    return b == kNone ? uint8_t{0} : block(b)[offset(p)];
  }

  uint8_t& at(int q, GridPoint p) {
    uint32_t& b = table_[slot(q, p)];
    if (b == kNone) b = allocate();
    return block(b)[offset(p)];
  }

 private:
  static constexpr int32_t kSide = 16;
  static constexpr uint32_t kBlockBytes = kSide * kSide, kChunkBlocks = 256;
  static constexpr uint32_t kNone = UINT32_MAX;

  size_t slot(int q, GridPoint p) const {
    return static_cast<size_t>(q) * per_quad_ +
           static_cast<size_t>((p.y / kSide) * columns_ + p.x / kSide);
  }
  static uint32_t offset(GridPoint p) { return (p.y % kSide) * kSide + p.x % kSide; }
  uint8_t* block(uint32_t b) const {
    return chunks_[b / kChunkBlocks].get() + (b % kChunkBlocks) * kBlockBytes;
  }
  uint32_t allocate() {
    const uint32_t b = used_++;
    if (b / kChunkBlocks == chunks_.size()) {
      chunks_.push_back(std::make_unique_for_overwrite<uint8_t[]>(kChunkBlocks * kBlockBytes));
    }
    std::fill_n(block(b), kBlockBytes, uint8_t{0});
    return b;
  }

  int32_t columns_ = 0;
  size_t per_quad_ = 0;
  std::vector<uint32_t> table_;  // per quad and block: its number, or kNone
  std::vector<std::unique_ptr<uint8_t[]>> chunks_;
  uint32_t used_ = 0;
};

}  // namespace relief::lod
