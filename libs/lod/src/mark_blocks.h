#pragma once
// The edge marks (one byte per diamond, 0 = undecided) of every quad of one
// refinement, stored in blocks allocated, zeroed, on the first write. A frame
// decides a small part of each quad's grid (a distant quad a few dozen marks
// of its 2^(2k+1) points): clearing whole grids, about 0.5 MB a quad of
// 512 x 256 samples, took more time than deciding the marks. Blocks are kept
// for the next reset(), so a thread that refines frame after frame
// (refine.cpp keeps one per thread) allocates nothing once warm. Addresses
// stay valid until reset().
#include <algorithm>
#include <cstdint>
#include <memory>
#include <vector>

#include "edge_marks.h"

namespace relief::lod {

// Marks by diamond slot (MarkGrid::slot: class by class, row by row
// within a class), in blocks of 256 slots: what refinement uses. Top-down, a
// frame reaches the coarse diamonds of every quad and the fine ones of a few:
// by grid point, each coarse mark took a 16 x 16 block of its own (a few
// dozen megabytes of blocks touched per frame, most of them missing the
// caches); by slot, a class's marks lie together. Only diamonds have slots:
// the halves' corners (always vertices) and samples' sides (never split) have
// no mark.
// Zeroed blocks of marks, kept for the next frame once allocated. One per
// thread that writes marks (refine_lanes.cpp's lanes each have their own).
class MarkBlocks {
 public:
  static constexpr uint32_t kBlockBytes = 256;

  void reset() { used_ = 0; }
  uint8_t* allocate() {
    const uint32_t b = used_++;
    if (b / kChunkBlocks == chunks_.size()) {
      chunks_.push_back(std::make_unique_for_overwrite<uint8_t[]>(kChunkBlocks * kBlockBytes));
    }
    uint8_t* block = chunks_[b / kChunkBlocks].get() + (b % kChunkBlocks) * kBlockBytes;
    std::fill_n(block, kBlockBytes, uint8_t{0});
    return block;
  }

 private:
  static constexpr uint32_t kChunkBlocks = 256;
  std::vector<std::unique_ptr<uint8_t[]>> chunks_;
  uint32_t used_ = 0;
};

class SlotMarks {
 public:
  void reset(const MarkGrid& grid, size_t quads) {
    per_quad_ = (grid.slots() + kBlockBytes - 1) / kBlockBytes;
    table_.assign(quads * per_quad_, nullptr);
    blocks_.reset();
  }

  uint8_t get(int q, uint32_t slot) const {
    const uint8_t* b = table_[block(q, slot)];
    return b ? b[slot % kBlockBytes] : uint8_t{0};
  }

  // A mark to write, its block taken from `blocks` if it has none yet. Threads
  // may write the marks of different quads at once, each with its own blocks.
  uint8_t& at(int q, uint32_t slot, MarkBlocks& blocks) {
    uint8_t*& b = table_[block(q, slot)];
    if (!b) b = blocks.allocate();
    return b[slot % kBlockBytes];
  }
  uint8_t& at(int q, uint32_t slot) { return at(q, slot, blocks_); }
  MarkBlocks& blocks() { return blocks_; }  // those at() takes from

  // A mark about to be read (if its block is there).
  void prefetch(int q, uint32_t slot) const {
    if (const uint8_t* b = table_[block(q, slot)]) __builtin_prefetch(b + slot % kBlockBytes);
  }

 private:
  static constexpr uint32_t kBlockBytes = MarkBlocks::kBlockBytes;

  size_t block(int q, uint32_t slot) const {
    return static_cast<size_t>(q) * per_quad_ + slot / kBlockBytes;
  }

  size_t per_quad_ = 0;
  std::vector<uint8_t*> table_;  // per quad and block: the block, or null
  MarkBlocks blocks_;
};

}  // namespace relief::lod
