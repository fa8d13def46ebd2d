#include "height_slopes.h"

#include <algorithm>
#include <bit>
#include <cassert>
#include <cmath>
#if defined(__x86_64__) || defined(__i386__)
#include <immintrin.h>
#endif

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

namespace {

// The clamped stencil: edge rows and columns (the GL clamps texels there).
void slopes_clamped(std::span<const float> heights, int width, int height, int y, int x0, int x1,
                    uint16_t* out) {
  auto at = [&](int x, int yy) {
    return heights[static_cast<size_t>(std::clamp(yy, 0, height - 1)) * width +
                   static_cast<size_t>(std::clamp(x, 0, width - 1))];
  };
  for (int x = x0; x < x1; ++x) {
    out[2 * x] = to_half(at(x + 1, y) - at(x - 1, y));
    out[2 * x + 1] = to_half(at(x, y + 1) - at(x, y - 1));
  }
}

#if defined(__x86_64__) || defined(__i386__)
// Eight to_half()s at once: F16C's conversion rounds to nearest even as
// to_half() does, and what to_half() does besides (saturation at 65504, NaN
// to 0) is done first, so every half is bit for bit to_half()'s.
__attribute__((target("avx2,f16c"))) inline __m128i halves(__m256 v) {
  v = _mm256_and_ps(v, _mm256_cmp_ps(v, v, _CMP_ORD_Q));  // NaN: +0
  v = _mm256_min_ps(_mm256_max_ps(v, _mm256_set1_ps(-65504.0f)), _mm256_set1_ps(65504.0f));
  return _mm256_cvtps_ph(v, _MM_FROUND_TO_NEAREST_INT | _MM_FROUND_NO_EXC);
}

// An interior row's slopes eight samples at a time, from x = 1 while eight
// are left before the last sample: the first x not done.
__attribute__((target("avx2,f16c"))) int slopes_row_f16c(const float* above, const float* row,
                                                         const float* below, int width,
                                                         uint16_t* out) {
  int x = 1;
  for (; x + 8 <= width - 1; x += 8) {
    const __m128i dx =
        halves(_mm256_sub_ps(_mm256_loadu_ps(row + x + 1), _mm256_loadu_ps(row + x - 1)));
    const __m128i dy =
        halves(_mm256_sub_ps(_mm256_loadu_ps(below + x), _mm256_loadu_ps(above + x)));
    auto* o = reinterpret_cast<__m128i*>(out + 2 * x);
    _mm_storeu_si128(o, _mm_unpacklo_epi16(dx, dy));
    _mm_storeu_si128(o + 1, _mm_unpackhi_epi16(dx, dy));
  }
  return x;
}

bool has_f16c() {
  static const bool yes = __builtin_cpu_supports("avx2") && __builtin_cpu_supports("f16c");
  return yes;
}
#endif

}  // namespace

std::vector<uint16_t> height_slopes(std::span<const float> heights, int width, int height) {
  assert(width > 0 && height > 0 && heights.size() == static_cast<size_t>(width) * height);
  std::vector<uint16_t> out(heights.size() * 2);
  for (int y = 0; y < height; ++y) {
    uint16_t* o = out.data() + static_cast<size_t>(y) * width * 2;
    if (y == 0 || y == height - 1 || width < 3) {
      slopes_clamped(heights, width, height, y, 0, width, o);
      continue;
    }
    // Interior rows: no clamping but at the first and last sample (a tile
    // uploads 132 k samples on the render thread: ~0.6 ms before this).
    const float* row = heights.data() + static_cast<size_t>(y) * width;
    const float *above = row - width, *below = row + width;
    int x = 1;
#if defined(__x86_64__) || defined(__i386__)
    if (has_f16c()) x = slopes_row_f16c(above, row, below, width, o);
#endif
    for (; x < width - 1; ++x) {
      o[2 * x] = to_half(row[x + 1] - row[x - 1]);
      o[2 * x + 1] = to_half(below[x] - above[x]);
    }
    slopes_clamped(heights, width, height, y, 0, 1, o);
    slopes_clamped(heights, width, height, y, width - 1, width, o);
  }
  return out;
}

}  // namespace relief::render
