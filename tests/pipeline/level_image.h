#pragma once
// One pyramid level of a Float32 store reassembled from its tile interiors
// into one image (NaN where there is no tile), for whole-level comparisons.
#include <cstdint>
#include <vector>

#include "relief/tiles/store.h"

namespace relief::testing {

struct LevelImage {
  int64_t x0 = 0, y0 = 0;  // global sample coordinates of (0, 0)
  int width = 0, height = 0;
  std::vector<float> v;
  float at(int64_t gx, int64_t gy) const;  // NaN outside
};

// `pad` extra NaN samples on every side.
LevelImage read_level(const tiles::Store& store, int level, int pad = 0);

}  // namespace relief::testing
