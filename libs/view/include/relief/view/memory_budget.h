#pragma once
// One budget for the tile caches a scene keeps in main memory
// (docs/streaming.md, "One memory budget"): the elevation's decoded tiles
// (L2), their diamond errors (edge marks), each texture's decoded tiles, and
// the GPU cache (L3) when the GL rasterises on the CPU (llvmpipe), whose
// texture arrays are main memory too. Split so that every cache holds about
// as many tiles as the others: a tile is drawn only when it is in all of
// them, so room for more in one is room wasted.
#include <cstdint>
#include <optional>

#include "relief/base/result.h"

namespace relief::view {

struct CacheUse {
  bool diamond_errors = false;  // edge-mark refinement keeps them per tile
  int textures = 0;             // imagery store or texture layers (a loader each)
  bool composites = false;      // texture layers: one composite per quad on L3
  bool gpu_in_memory = false;   // software rasteriser: L3 counts
  // L3's budget as given (--gpu-budget); counted against the total when L3
  // is main memory, left out of it otherwise. Unset: L3 gets its share.
  std::optional<uint64_t> gpu_given;
};

struct CacheBudgets {
  uint64_t elevation = 0;       // decoded elevation tiles
  uint64_t diamond_errors = 0;  // 0 when no refinement keeps them
  uint64_t texture_each = 0;    // each texture loader's decoded tiles
  std::optional<uint64_t> gpu;  // L3, when the total decides it
};

// Smallest total accepted: a few tiles in each cache.
inline constexpr uint64_t kMinimumMemoryBudget = uint64_t{16} << 20;

// Splits `total` bytes by each cache's bytes per sample of a tile: decoded
// float heights 4, diamond errors 16, an RGBA texture 4, L3 8 for heights with
// their slopes and 4 per imagery or composite array. Fails (naming
// --memory-budget) when the total is below kMinimumMemoryBudget or leaves
// less than that beside a given L3.
Result<CacheBudgets> split_memory_budget(uint64_t total, const CacheUse& use);

}  // namespace relief::view
