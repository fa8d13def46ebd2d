#pragma once
#include <cmath>
#include <limits>
#include <random>

#include "relief/tiles/raster.h"

namespace relief::tiles::testing {

// A smooth terrain-like surface with some NaN holes.
inline Raster terrain(int w, int h, unsigned seed = 1, bool holes = true) {
  Raster r(SampleType::Float32, 1, w, h);
  std::mt19937 rng(seed);
  std::uniform_real_distribution<float> noise(-0.5f, 0.5f);
  auto v = r.f32();
  for (int j = 0; j < h; ++j) {
    for (int i = 0; i < w; ++i) {
      v[static_cast<size_t>(j * w + i)] =
          1000.0f + 300.0f * std::sin(i * 0.05f) * std::cos(j * 0.07f) + noise(rng);
    }
  }
  if (holes) {
    for (int k = 0; k < w * h / 50; ++k)
      v[rng() % v.size()] = std::numeric_limits<float>::quiet_NaN();
  }
  return r;
}

inline Raster image(int w, int h) {
  Raster r(SampleType::UInt8, 4, w, h);
  auto p = r.u8();
  for (int j = 0; j < h; ++j) {
    for (int i = 0; i < w; ++i) {
      const size_t o = static_cast<size_t>(j * w + i) * 4;
      p[o] = static_cast<uint8_t>(i * 3);
      p[o + 1] = static_cast<uint8_t>(j * 5);
      p[o + 2] = static_cast<uint8_t>((i + j) * 2);
      p[o + 3] = (i < 10) ? 0 : 255;
    }
  }
  return r;
}

}  // namespace relief::tiles::testing
