#include "relief/tiles/raster.h"

#include <cassert>
#include <cmath>
#include <cstring>
#include <limits>

#include <fmt/format.h>

#include "relief/base/memory_use.h"

namespace relief::tiles {

std::string_view to_string(SampleType t) {
  switch (t) {
    case SampleType::Float32:
      return "float32";
    case SampleType::UInt8:
      return "uint8";
  }
  return "?";
}

Result<SampleType> sample_type_from_string(std::string_view s) {
  if (s == "float32") return SampleType::Float32;
  if (s == "uint8") return SampleType::UInt8;
  return fail(fmt::format("unknown sample type '{}'", s));
}

size_t sample_size(SampleType t) {
  return t == SampleType::Float32 ? 4 : 1;
}

Raster::Raster(Uninitialised, SampleType type, int bands, int width, int height)
    : type_(type), bands_(bands), width_(width), height_(height) {
  assert(width >= 0 && height >= 0 && bands > 0);
  bytes_.resize(pixel_count() * static_cast<size_t>(bands) * sample_size(type));
  populate_pages(bytes_.data(), bytes_.size());  // a tile's 128 pages in one call
}

Raster::Raster(SampleType type, int bands, int width, int height)
    : Raster(Uninitialised{}, type, bands, width, height) {
  std::fill(bytes_.begin(), bytes_.end(), std::byte{0});
}

Raster Raster::uninitialised(SampleType type, int bands, int width, int height) {
  return Raster(Uninitialised{}, type, bands, width, height);
}

Raster Raster::empty(SampleType type, int width, int height) {
  if (type == SampleType::Float32) {
    Raster r = uninitialised(type, 1, width, height);
    auto v = r.f32();
    std::fill(v.begin(), v.end(), std::numeric_limits<float>::quiet_NaN());
    return r;
  }
  return Raster(type, 4, width, height);  // zero: transparent
}

std::span<float> Raster::f32() {
  assert(type_ == SampleType::Float32);
  return {reinterpret_cast<float*>(bytes_.data()), bytes_.size() / 4};
}
std::span<const float> Raster::f32() const {
  assert(type_ == SampleType::Float32);
  return {reinterpret_cast<const float*>(bytes_.data()), bytes_.size() / 4};
}
std::span<uint8_t> Raster::u8() {
  assert(type_ == SampleType::UInt8);
  return {reinterpret_cast<uint8_t*>(bytes_.data()), bytes_.size()};
}
std::span<const uint8_t> Raster::u8() const {
  assert(type_ == SampleType::UInt8);
  return {reinterpret_cast<const uint8_t*>(bytes_.data()), bytes_.size()};
}

bool Raster::valid(int i, int j) const {
  const size_t p = static_cast<size_t>(j) * static_cast<size_t>(width_) + static_cast<size_t>(i);
  if (type_ == SampleType::Float32) return !std::isnan(f32()[p]);
  return u8()[p * 4 + 3] != 0;
}

SampleStats Raster::stats(int x0, int y0, int w, int h) const {
  SampleStats s;
  double sum = 0, sum_sq = 0;
  double lo = std::numeric_limits<double>::infinity(), hi = -lo;
  uint64_t n = 0;
  const size_t stride = static_cast<size_t>(width_);
  if (type_ == SampleType::Float32) {
    const float* v = reinterpret_cast<const float*>(bytes_.data());
    for (int j = y0; j < y0 + h; ++j) {
      const float* row = v + static_cast<size_t>(j) * stride;
      double row_sum = 0, row_sq = 0;
      for (int i = x0; i < x0 + w; ++i) {
        const float x = row[i];
        if (std::isnan(x)) continue;
        row_sum += x;
        row_sq += static_cast<double>(x) * x;
        lo = std::min(lo, static_cast<double>(x));
        hi = std::max(hi, static_cast<double>(x));
        ++n;
      }
      sum += row_sum;
      sum_sq += row_sq;
    }
    s.valid_count = n;
  } else {
    const uint8_t* p = reinterpret_cast<const uint8_t*>(bytes_.data());
    for (int j = y0; j < y0 + h; ++j) {
      const uint8_t* row = p + static_cast<size_t>(j) * stride * 4;
      for (int i = x0; i < x0 + w; ++i) {
        const uint8_t* px = row + static_cast<size_t>(i) * 4;
        if (px[3] == 0) continue;
        ++s.valid_count;
        for (int b = 0; b < 3; ++b) {
          const double x = px[b];
          sum += x;
          sum_sq += x * x;
          lo = std::min(lo, x);
          hi = std::max(hi, x);
        }
        n += 3;
      }
    }
  }
  if (n == 0) return s;
  s.min = lo;
  s.max = hi;
  s.mean = sum / static_cast<double>(n);
  s.stddev = std::sqrt(std::max(0.0, sum_sq / static_cast<double>(n) - s.mean * s.mean));
  return s;
}

bool Raster::any_valid() const {
  if (type_ == SampleType::Float32) {
    for (float x : f32()) {
      if (!std::isnan(x)) return true;
    }
    return false;
  }
  const auto p = u8();
  for (size_t i = 3; i < p.size(); i += 4) {
    if (p[i] != 0) return true;
  }
  return false;
}

void Raster::copy_from(const Raster& src, int sx, int sy, int dx, int dy, int w, int h) {
  assert(src.type_ == type_ && src.bands_ == bands_);
  assert(sx >= 0 && sy >= 0 && sx + w <= src.width_ && sy + h <= src.height_);
  assert(dx >= 0 && dy >= 0 && dx + w <= width_ && dy + h <= height_);
  const size_t px = static_cast<size_t>(bands_) * sample_size(type_);
  for (int r = 0; r < h; ++r) {
    const std::byte* from =
        src.bytes_.data() + (static_cast<size_t>(sy + r) * src.width_ + sx) * px;
    std::byte* to = bytes_.data() + (static_cast<size_t>(dy + r) * width_ + dx) * px;
    std::memcpy(to, from, static_cast<size_t>(w) * px);
  }
}

}  // namespace relief::tiles
