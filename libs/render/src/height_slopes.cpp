#include "height_slopes.h"

#include <algorithm>
#include <bit>
#include <cassert>
#include <cmath>

namespace relief::render {

uint16_t to_half(float f) {
  if (std::isnan(f)) return 0;
  const uint32_t x = std::bit_cast<uint32_t>(f);
  const auto sign = static_cast<uint16_t>((x >> 16) & 0x8000u);
  const uint32_t magnitude = x & 0x7fffffffu;
  if (magnitude >= 0x477ff000u) return sign | 0x7bffu;  // rounds past 65504: saturate
  if (magnitude < 0x38800000u) {  // below 2^-14: a subnormal half, in units of 2^-24
    const float units = std::bit_cast<float>(magnitude) * 16777216.0f;  // exact: a power of 2
    return sign | static_cast<uint16_t>(std::nearbyint(units));         // ties to even
  }
  // Rebias the exponent (127 - 15), then round the 23-bit significand to 10 bits.
  uint32_t h = magnitude - (112u << 23);
  h += 0xfffu + ((h >> 13) & 1u);
  return sign | static_cast<uint16_t>(h >> 13);
}

std::vector<uint16_t> height_slopes(std::span<const float> heights, int width, int height) {
  assert(width > 0 && height > 0 && heights.size() == static_cast<size_t>(width) * height);
  std::vector<uint16_t> out(heights.size() * 2);
  auto at = [&](int x, int y) {
    return heights[static_cast<size_t>(std::clamp(y, 0, height - 1)) * width +
                   static_cast<size_t>(std::clamp(x, 0, width - 1))];
  };
  for (int y = 0; y < height; ++y) {
    for (int x = 0; x < width; ++x) {
      const size_t i = (static_cast<size_t>(y) * width + static_cast<size_t>(x)) * 2;
      out[i] = to_half(at(x + 1, y) - at(x - 1, y));
      out[i + 1] = to_half(at(x, y + 1) - at(x, y - 1));
    }
  }
  return out;
}

}  // namespace relief::render
