#pragma once
// An in-memory grid of samples: the unit every codec, tile and operator sees.
//
// Two sample types cover every dataset kind:
//  - Float32, 1 band: elevation (metres) and SAR amplitude; nodata is NaN.
//  - UInt8, 4 bands (R, G, B, A), pixel-interleaved: imagery; alpha 0 is nodata.
#include <cstddef>
#include <cstdint>
#include <span>
#include <string_view>
#include <vector>

#include "relief/base/result.h"

namespace relief::tiles {

enum class SampleType : uint8_t { Float32 = 1, UInt8 = 2 };

std::string_view to_string(SampleType t);
Result<SampleType> sample_type_from_string(std::string_view s);
size_t sample_size(SampleType t);

struct SampleStats {
  double min = 0, max = 0, mean = 0, stddev = 0;
  uint64_t valid_count = 0;
};

class Raster {
 public:
  Raster() = default;
  Raster(SampleType type, int bands, int width, int height);
  // A Float32 raster filled with NaN, or a UInt8 RGBA raster of transparent pixels.
  static Raster empty(SampleType type, int width, int height);

  SampleType type() const { return type_; }
  int bands() const { return bands_; }
  int width() const { return width_; }
  int height() const { return height_; }
  size_t pixel_count() const { return static_cast<size_t>(width_) * static_cast<size_t>(height_); }
  size_t byte_size() const { return bytes_.size(); }

  std::span<std::byte> bytes() { return bytes_; }
  std::span<const std::byte> bytes() const { return bytes_; }
  std::span<float> f32();
  std::span<const float> f32() const;
  std::span<uint8_t> u8();
  std::span<const uint8_t> u8() const;

  bool valid(int i, int j) const;
  bool any_valid() const;
  // Statistics of the valid samples in the window [x0, x0+w) x [y0, y0+h).
  // For imagery they are over all colour channels of valid pixels.
  SampleStats stats(int x0, int y0, int w, int h) const;
  // Copies the window of `src` starting at (sx, sy) of size w x h to (dx, dy).
  void copy_from(const Raster& src, int sx, int sy, int dx, int dy, int w, int h);

 private:
  SampleType type_ = SampleType::Float32;
  int bands_ = 0, width_ = 0, height_ = 0;
  std::vector<std::byte> bytes_;
};

}  // namespace relief::tiles
