#pragma once
// What refinement needs to know about every diamond of a quad (edge_marks.h)
// that depends only on the quad's data tile, computed once per tile:
//
// - error: the largest |interpolation of the diamond's two triangles - full
//   mesh| over the full mesh's vertices (sample centres and corners) in the
//   diamond: both are linear on each full-mesh triangle, so this bounds the
//   distance everywhere in it. Saturated: at least each child's (inside the
//   quad), so a diamond that must split has parents that must too, and
//   top-down refinement finds everything bottom-up refinement does.
// - lo, hi: the heights of the full mesh in the diamond, saturated likewise
//   (nested boxes), rounded outwards to whole metres.
//
// For diamonds on the quad's border, only the half inside the quad (the other
// is in the neighbour's tile). Heights are the tile's own (bilinear, as the
// vertex shader computes them); sides taking a coarser neighbour's data are
// accounted for per frame.
#include <cstdint>
#include <list>
#include <memory>
#include <unordered_map>
#include <utility>
#include <vector>

#include "edge_marks.h"
#include "relief/base/result.h"
#include "relief/tiles/raster.h"

namespace relief::lod {

// No member initializers: DiamondErrors::at is allocated uninitialized.
struct DiamondError {
  float error;     // metres
  int16_t lo, hi;  // metres
};

// Allocates without value-initializing: measure_diamonds writes every slot,
// and a 2 MB memset of fresh pages was a tenth of its time.
template <class T>
struct UninitializedAllocator : std::allocator<T> {
  template <class U>
  struct rebind {
    using other = UninitializedAllocator<U>;
  };
  template <class U, class... Args>
  void construct(U* p, Args&&... args) {
    if constexpr (sizeof...(Args) == 0) {
      ::new (static_cast<void*>(p)) U;
    } else {
      ::new (static_cast<void*>(p)) U(std::forward<Args>(args)...);
    }
  }
};

struct DiamondErrors {
  // By MarkGrid::slot; together, as refinement reads them: one cache line.
  std::vector<DiamondError, UninitializedAllocator<DiamondError>> at;
  uint64_t bytes() const { return at.size() * sizeof(DiamondError); }
};

// The errors of the diamonds of quad `key` (a quad of the store, level <=
// its finest) from its bordered tile.
DiamondErrors measure_diamonds(const MarkGrid& grid, const tiles::Raster& tile, int border);

}  // namespace relief::lod
