#pragma once
// An in-memory grid of samples: the unit every codec, tile and operator sees.
//
// Two sample types cover every dataset kind:
//  - Float32, 1 band: elevation (metres) and SAR amplitude; nodata is NaN.
//  - UInt8, 4 bands (R, G, B, A), pixel-interleaved: imagery; alpha 0 is nodata.
#include <cstddef>
#include <cstdint>
#include <memory>
#include <span>
#include <string_view>
#include <utility>
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

// Leaves the elements a vector grows by uninitialised, so that a raster's
// samples are written once, by whoever says what they hold: zeroing half a
// megabyte a tile and then filling it again cost a build of the Himalaya
// block a tenth of its CPU time.
template <class T>
struct UninitialisedAllocator : std::allocator<T> {
  template <class U>
  struct rebind {
    using other = UninitialisedAllocator<U>;
  };
  UninitialisedAllocator() = default;
  template <class U>
  UninitialisedAllocator(const UninitialisedAllocator<U>&) noexcept {}
  template <class U>
  void construct(U* p) noexcept {
    ::new (static_cast<void*>(p)) U;
  }
  template <class U, class... Args>
  void construct(U* p, Args&&... args) {
    ::new (static_cast<void*>(p)) U(std::forward<Args>(args)...);
  }
};

class Raster {
 public:
  Raster() = default;
  // Every sample zero.
  Raster(SampleType type, int bands, int width, int height);
  // A Float32 raster filled with NaN, or a UInt8 RGBA raster of transparent pixels.
  static Raster empty(SampleType type, int width, int height);
  // Samples left undefined: for a caller that writes every one of them.
  static Raster uninitialised(SampleType type, int bands, int width, int height);

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
  struct Uninitialised {};
  Raster(Uninitialised, SampleType type, int bands, int width, int height);

  std::vector<std::byte, UninitialisedAllocator<std::byte>> bytes_;
};

}  // namespace relief::tiles
