#include "pyramid.h"

#include <algorithm>
#include <cassert>
#include <cmath>
#include <limits>

namespace relief::ingest {
namespace {

void downsample_float(const tiles::Raster& child, tiles::Raster& parent, int ox, int oy) {
  const int cw = child.width();
  const int pw = parent.width();
  auto in = child.f32();
  auto out = parent.f32();
  for (int j = 0; j < child.height() / 2; ++j) {
    for (int i = 0; i < cw / 2; ++i) {
      const size_t a = static_cast<size_t>(2 * j) * cw + 2 * i;
      const float v[4] = {in[a], in[a + 1], in[a + cw], in[a + cw + 1]};
      float& o = out[static_cast<size_t>(oy + j) * pw + ox + i];
      // All four valid (nearly always): the loop's sum in its order, and a
      // quarter of it, exactly the division by 4 (a power of two), without
      // the loop's branches.
      if (!(std::isnan(v[0]) || std::isnan(v[1]) || std::isnan(v[2]) || std::isnan(v[3]))) {
        const double sum = ((static_cast<double>(v[0]) + v[1]) + v[2]) + v[3];
        o = static_cast<float>(sum * 0.25);
        continue;
      }
      double sum = 0;
      int n = 0;
      for (float x : v) {
        if (!std::isnan(x)) {
          sum += x;
          ++n;
        }
      }
      o = n ? static_cast<float>(sum / n) : std::numeric_limits<float>::quiet_NaN();
    }
  }
}

void downsample_rgba(const tiles::Raster& child, tiles::Raster& parent, int ox, int oy) {
  const int cw = child.width();
  const int pw = parent.width();
  auto in = child.u8();
  auto out = parent.u8();
  for (int j = 0; j < child.height() / 2; ++j) {
    for (int i = 0; i < cw / 2; ++i) {
      const size_t a = static_cast<size_t>(2 * j) * cw + 2 * i;
      const size_t px[4] = {a, a + 1, a + cw, a + cw + 1};
      unsigned sum[3] = {0, 0, 0}, alpha = 0, n = 0;
      for (size_t p : px) {
        const uint8_t* c = &in[p * 4];
        alpha += c[3];
        if (c[3] == 0) continue;
        for (int b = 0; b < 3; ++b) sum[b] += c[b];
        ++n;
      }
      uint8_t* o = &out[(static_cast<size_t>(oy + j) * pw + ox + i) * 4];
      if (n == 0) continue;  // stays transparent
      for (int b = 0; b < 3; ++b) o[b] = static_cast<uint8_t>((sum[b] + n / 2) / n);
      // Coverage: mean alpha of the four children, never 0 when one is valid.
      o[3] = static_cast<uint8_t>(std::max(1u, (alpha + 2) / 4));
    }
  }
}

}  // namespace

tiles::Raster downsample(const std::array<const tiles::Raster*, 4>& children, int width, int height,
                         tiles::SampleType type) {
  // Four children of elevation write every sample of the parent; otherwise
  // what no child covers stays nodata (and so does imagery's no-sample pixel).
  const bool all = std::all_of(children.begin(), children.end(), [](auto* c) { return c; });
  tiles::Raster parent = all && type == tiles::SampleType::Float32
                             ? tiles::Raster::uninitialised(type, 1, width, height)
                             : tiles::Raster::empty(type, width, height);
  for (int c = 0; c < 4; ++c) {
    const tiles::Raster* child = children[static_cast<size_t>(c)];
    if (!child) continue;
    assert(child->width() == width && child->height() == height);
    const int ox = (c % 2) * width / 2, oy = (c / 2) * height / 2;
    if (type == tiles::SampleType::Float32)
      downsample_float(*child, parent, ox, oy);
    else
      downsample_rgba(*child, parent, ox, oy);
  }
  return parent;
}

}  // namespace relief::ingest
