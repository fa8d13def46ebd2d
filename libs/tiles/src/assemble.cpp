#include "relief/tiles/assemble.h"

#include <algorithm>
#include <cassert>
#include <cmath>
#include <limits>

namespace relief::tiles {

Raster assemble_bordered(const std::array<const Raster*, 9>& neighbours, int width, int height,
                         int border, SampleType type) {
  assert(border <= width && border <= height);
  // With all nine neighbours every sample is copied from one of them.
  const bool all = std::all_of(neighbours.begin(), neighbours.end(), [](auto* n) { return n; });
  Raster out = all ? Raster::uninitialised(type, type == SampleType::Float32 ? 1 : 4,
                                           width + 2 * border, height + 2 * border)
                   : Raster::empty(type, width + 2 * border, height + 2 * border);
  // Source start and destination start along one axis for offsets -1, 0, +1.
  auto span = [border](int d, int size, int& src, int& dst, int& len) {
    if (d < 0) {
      src = size - border;
      dst = 0;
      len = border;
    } else if (d == 0) {
      src = 0;
      dst = border;
      len = size;
    } else {
      src = 0;
      dst = border + size;
      len = border;
    }
  };
  for (int dy = -1; dy <= 1; ++dy) {
    for (int dx = -1; dx <= 1; ++dx) {
      const Raster* n = neighbours[static_cast<size_t>((dy + 1) * 3 + dx + 1)];
      if (!n || (border == 0 && (dx || dy))) continue;
      int sx, tx, w, sy, ty, h;
      span(dx, width, sx, tx, w);
      span(dy, height, sy, ty, h);
      out.copy_from(*n, sx, sy, tx, ty, w, h);
    }
  }
  return out;
}

SampleStats combine_stats(std::span<const SampleStats> parts, int channels) {
  double count = 0, sum = 0, sum_sq = 0;
  double lo = std::numeric_limits<double>::infinity(), hi = -lo;
  uint64_t valid = 0;
  for (const SampleStats& t : parts) {
    if (t.valid_count == 0) continue;
    const double n = static_cast<double>(t.valid_count) * channels;
    count += n;
    sum += t.mean * n;
    sum_sq += (t.stddev * t.stddev + t.mean * t.mean) * n;
    lo = std::min(lo, t.min);
    hi = std::max(hi, t.max);
    valid += t.valid_count;
  }
  SampleStats s;
  if (count == 0) return s;
  s.min = lo;
  s.max = hi;
  s.mean = sum / count;
  s.stddev = std::sqrt(std::max(0.0, sum_sq / count - s.mean * s.mean));
  s.valid_count = valid;
  return s;
}

}  // namespace relief::tiles
