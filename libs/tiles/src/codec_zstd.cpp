// Lossless codec: a horizontal difference predictor on the raw bit patterns
// (exact for floats, NaN included), then the bytes of each sample split into
// planes so zstd sees long runs of similar high bytes.
#include <zstd.h>

#include <cstring>

#include <fmt/format.h>

#include "relief/tiles/codec.h"

namespace relief::tiles::detail {
namespace {

// Number of interleaved channels and bytes per channel of a raster's samples.
struct Shape {
  size_t channels, bytes_per_sample, width, height;
  size_t total() const { return channels * bytes_per_sample * width * height; }
};

Shape shape_of(SampleType t, int bands, int w, int h) {
  return {static_cast<size_t>(bands), sample_size(t), static_cast<size_t>(w),
          static_cast<size_t>(h)};
}

// Predicts each sample from its left neighbour in the same channel (as unsigned
// integers with wrap-around) and writes byte plane k of all residuals together.
void forward(const std::byte* in, std::byte* out, const Shape& s) {
  const size_t n = s.width * s.height * s.channels;
  for (size_t idx = 0; idx < n; ++idx) {
    const size_t col = (idx / s.channels) % s.width;
    uint32_t v = 0, prev = 0;
    std::memcpy(&v, in + idx * s.bytes_per_sample, s.bytes_per_sample);
    if (col > 0) std::memcpy(&prev, in + (idx - s.channels) * s.bytes_per_sample, s.bytes_per_sample);
    const uint32_t residual = v - prev;
    for (size_t b = 0; b < s.bytes_per_sample; ++b) {
      out[b * n + idx] = static_cast<std::byte>((residual >> (8 * b)) & 0xFF);
    }
  }
}

void inverse(const std::byte* in, std::byte* out, const Shape& s) {
  const size_t n = s.width * s.height * s.channels;
  const uint32_t mask = s.bytes_per_sample == 4 ? 0xFFFFFFFFu : (1u << (8 * s.bytes_per_sample)) - 1;
  for (size_t idx = 0; idx < n; ++idx) {
    const size_t col = (idx / s.channels) % s.width;
    uint32_t residual = 0, prev = 0;
    for (size_t b = 0; b < s.bytes_per_sample; ++b) {
      residual |= static_cast<uint32_t>(in[b * n + idx]) << (8 * b);
    }
    if (col > 0) std::memcpy(&prev, out + (idx - s.channels) * s.bytes_per_sample, s.bytes_per_sample);
    const uint32_t v = (residual + prev) & mask;
    std::memcpy(out + idx * s.bytes_per_sample, &v, s.bytes_per_sample);
  }
}

}  // namespace

Result<std::vector<std::byte>> encode_zstd(const Raster& r, int level) {
  const Shape s = shape_of(r.type(), r.bands(), r.width(), r.height());
  std::vector<std::byte> planes(s.total());
  forward(r.bytes().data(), planes.data(), s);
  std::vector<std::byte> out(ZSTD_compressBound(planes.size()));
  const size_t n = ZSTD_compress(out.data(), out.size(), planes.data(), planes.size(), level);
  if (ZSTD_isError(n)) return fail(fmt::format("zstd: {}", ZSTD_getErrorName(n)));
  out.resize(n);
  return out;
}

Result<Raster> decode_zstd(std::span<const std::byte> p, SampleType t, int bands, int w, int h) {
  const Shape s = shape_of(t, bands, w, h);
  const unsigned long long size = ZSTD_getFrameContentSize(p.data(), p.size());
  if (size == ZSTD_CONTENTSIZE_ERROR || size == ZSTD_CONTENTSIZE_UNKNOWN || size != s.total()) {
    return fail("zstd payload is corrupt or has the wrong size");
  }
  std::vector<std::byte> planes(s.total());
  const size_t n = ZSTD_decompress(planes.data(), planes.size(), p.data(), p.size());
  if (ZSTD_isError(n) || n != planes.size()) {
    return fail(fmt::format("zstd payload is corrupt: {}",
                            ZSTD_isError(n) ? ZSTD_getErrorName(n) : "short"));
  }
  Raster r(t, bands, w, h);
  inverse(planes.data(), r.bytes().data(), s);
  return r;
}

}  // namespace relief::tiles::detail
