// Lossless codec: a predictor, then zstd.
//  - Float32: the floating-point predictor of TIFF (PREDICTOR=3): each row's
//    samples are split into byte planes, most significant byte first, and each
//    byte is replaced by its difference from the previous byte of the row.
//    Exact for every bit pattern, NaN included.
//  - UInt8 RGBA: channels are split into planes, each row differenced.
#include <zstd.h>

#include <bit>
#include <cstdlib>
#include <cstring>

#include <fmt/format.h>

#include "relief/tiles/codec.h"

namespace relief::tiles::detail {
namespace {

// Bytes of 4 consecutive little-endian floats, one plane at a time: word b
// holds byte (3 - b) of each sample, in sample order (a 4 x 4 byte transpose).
void split_planes4(const uint8_t* in, uint8_t* plane, size_t w) {
  uint32_t v[4];
  std::memcpy(v, in, sizeof v);
  const uint32_t p[4] = {
      (v[0] >> 24) | ((v[1] >> 16) & 0xff00u) | ((v[2] >> 8) & 0xff0000u) | (v[3] & 0xff000000u),
      ((v[0] >> 16) & 0xffu) | ((v[1] >> 8) & 0xff00u) | (v[2] & 0xff0000u) |
          ((v[3] << 8) & 0xff000000u),
      ((v[0] >> 8) & 0xffu) | (v[1] & 0xff00u) | ((v[2] << 8) & 0xff0000u) |
          ((v[3] << 16) & 0xff000000u),
      (v[0] & 0xffu) | ((v[1] << 8) & 0xff00u) | ((v[2] << 16) & 0xff0000u) | (v[3] << 24)};
  for (size_t b = 0; b < 4; ++b) std::memcpy(plane + b * w, &p[b], 4);
}

// out[k] = in[k] - in[k - 1] for k >= 1, eight bytes at a time: a byte-wise
// subtraction in a 64-bit word, no borrow between bytes (Hacker's Delight 2-18).
void difference(const uint8_t* in, uint8_t* out, size_t n) {
  constexpr uint64_t kHigh = 0x8080808080808080ull;
  out[0] = in[0];
  size_t k = 1;
  for (; k + 8 <= n; k += 8) {
    uint64_t cur, prev;
    std::memcpy(&cur, in + k, 8);
    std::memcpy(&prev, in + k - 1, 8);
    const uint64_t d = (((cur | kHigh) - (prev & ~kHigh)) ^ ((cur ^ ~prev) & kHigh));
    std::memcpy(out + k, &d, 8);
  }
  for (; k < n; ++k) out[k] = static_cast<uint8_t>(in[k] - in[k - 1]);
}

void forward_float(const Raster& r, std::vector<uint8_t>& out, std::vector<uint8_t>& row_planes) {
  static_assert(std::endian::native == std::endian::little, "byte planes assume little-endian");
  const size_t w = static_cast<size_t>(r.width()), h = static_cast<size_t>(r.height());
  const auto* in = reinterpret_cast<const uint8_t*>(r.bytes().data());
  out.resize(w * h * 4);  // no shrink: the buffers are reused across tiles
  row_planes.resize(w * 4);
  uint8_t* planes = row_planes.data();
  // Word-wide transposes and differences instead of byte loops: the byte
  // version took 6 % of a build's CPU time.
  for (size_t j = 0; j < h; ++j) {
    const uint8_t* row = in + j * w * 4;
    size_t i = 0;
    for (; i + 4 <= w; i += 4) split_planes4(row + i * 4, planes + i, w);
    for (; i < w; ++i) {
      for (size_t b = 0; b < 4; ++b) planes[b * w + i] = row[i * 4 + (3 - b)];
    }
    difference(planes, out.data() + j * w * 4, w * 4);
  }
}

void inverse_float(const uint8_t* in, Raster& r) {
  const size_t w = static_cast<size_t>(r.width()), h = static_cast<size_t>(r.height());
  auto* out = reinterpret_cast<uint8_t*>(r.bytes().data());
  std::vector<uint8_t> row(w * 4);
  for (size_t j = 0; j < h; ++j) {
    const uint8_t* src = in + j * w * 4;
    uint8_t acc = 0;
    for (size_t k = 0; k < w * 4; ++k) row[k] = acc = static_cast<uint8_t>(acc + src[k]);
    uint8_t* o = out + j * w * 4;
    for (size_t i = 0; i < w; ++i) {
      for (size_t b = 0; b < 4; ++b) o[i * 4 + (3 - b)] = row[b * w + i];
    }
  }
}

void forward_rgba(const Raster& r, std::vector<uint8_t>& out) {
  const size_t w = static_cast<size_t>(r.width()), h = static_cast<size_t>(r.height());
  const uint8_t* in = r.u8().data();
  out.resize(w * h * 4);
  for (size_t c = 0; c < 4; ++c) {
    uint8_t* plane = out.data() + c * w * h;
    for (size_t j = 0; j < h; ++j) {
      uint8_t prev = 0;
      for (size_t i = 0; i < w; ++i) {
        const uint8_t v = in[(j * w + i) * 4 + c];
        plane[j * w + i] = static_cast<uint8_t>(v - prev);
        prev = v;
      }
    }
  }
}

void inverse_rgba(const uint8_t* in, Raster& r) {
  const size_t w = static_cast<size_t>(r.width()), h = static_cast<size_t>(r.height());
  uint8_t* out = r.u8().data();
  for (size_t c = 0; c < 4; ++c) {
    const uint8_t* plane = in + c * w * h;
    for (size_t j = 0; j < h; ++j) {
      uint8_t acc = 0;
      for (size_t i = 0; i < w; ++i) {
        acc = static_cast<uint8_t>(acc + plane[j * w + i]);
        out[(j * w + i) * 4 + c] = acc;
      }
    }
  }
}

// zstd contexts are large (about 1 MiB at level 3) and costly to set up, so
// each thread keeps one of each for its lifetime, as does the plane buffer.
struct ThreadState {
  ZSTD_CCtx* cctx = ZSTD_createCCtx();
  ZSTD_DCtx* dctx = ZSTD_createDCtx();
  std::vector<uint8_t> planes;
  std::vector<uint8_t> row_planes;
  std::vector<std::byte> compressed;
  ~ThreadState() {
    ZSTD_freeCCtx(cctx);
    ZSTD_freeDCtx(dctx);
  }
};
ThreadState& thread_state() {
  thread_local ThreadState state;
  return state;
}

}  // namespace

Result<std::vector<std::byte>> encode_zstd(const Raster& r, int level) {
  ThreadState& ts = thread_state();
  std::vector<uint8_t>& planes = ts.planes;
  if (r.type() == SampleType::Float32)
    forward_float(r, planes, ts.row_planes);
  else
    forward_rgba(r, planes);
  // Compressed into the thread's buffer, then copied at its real size,
  // instead of zero-filling a fresh vector of the worst-case size per tile.
  std::vector<std::byte>& bound = ts.compressed;
  bound.resize(ZSTD_compressBound(planes.size()));
  const size_t n =
      ZSTD_compressCCtx(ts.cctx, bound.data(), bound.size(), planes.data(), planes.size(), level);
  if (ZSTD_isError(n)) return fail(fmt::format("zstd: {}", ZSTD_getErrorName(n)));
  return std::vector<std::byte>(bound.begin(), bound.begin() + static_cast<std::ptrdiff_t>(n));
}

Result<Raster> decode_zstd(std::span<const std::byte> p, SampleType t, int bands, int w, int h) {
  // The frame's own content size must be the header's, checked before allocating.
  const size_t expected =
      static_cast<size_t>(w) * static_cast<size_t>(h) * static_cast<size_t>(bands) * sample_size(t);
  const unsigned long long size = ZSTD_getFrameContentSize(p.data(), p.size());
  if (size == ZSTD_CONTENTSIZE_ERROR || size == ZSTD_CONTENTSIZE_UNKNOWN || size != expected) {
    return fail("zstd payload is corrupt or has the wrong size");
  }
  Raster r(t, bands, w, h);
  ThreadState& ts = thread_state();
  std::vector<uint8_t>& planes = ts.planes;
  planes.resize(r.byte_size());
  const size_t n = ZSTD_decompressDCtx(ts.dctx, planes.data(), planes.size(), p.data(), p.size());
  if (ZSTD_isError(n) || n != planes.size()) {
    return fail(fmt::format("zstd payload is corrupt: {}",
                            ZSTD_isError(n) ? ZSTD_getErrorName(n) : "short"));
  }
  if (t == SampleType::Float32)
    inverse_float(planes.data(), r);
  else
    inverse_rgba(planes.data(), r);
  return r;
}

}  // namespace relief::tiles::detail
