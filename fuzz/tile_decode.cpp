// Fuzz target: a tile file, from its 80-byte header through every codec
// (zstd + predictor, LERC, PNG, JPEG + alpha, WebP). Decoding must fail with a
// message or give a raster of exactly the shape the header states.
//
// Each input is decoded twice: as it is, and with both CRC-32s recomputed, so
// that mutations get past the checksums to the header fields and the codecs
// (a remote or damaged store can hold a tile whose checksums are right).
#include <algorithm>
#include <cstring>
#include <span>
#include <vector>

#include "fuzz_check.h"
#include "relief/tiles/tile_file.h"

namespace {

using namespace relief::tiles;

// Readers check a header's tile size against the manifest before decoding
// (issue 11: a forged 65535 x 65535 header must not allocate 17 GB); this
// target stands for such a reader with a bound well above any store's tiles.
constexpr size_t kMaxPixels = size_t{1} << 20;

// The shape a store would expect: the header's own when plausible (so the
// codecs are reached), else a default store shape (so the header check is).
TileShape expected_shape(std::span<const std::byte> bytes) {
  auto h = parse_tile_header(bytes, "fuzz.rtile");
  if (!h || size_t{h->width} * h->height > kMaxPixels) return {SampleType::Float32, 1, 530, 274, 9};
  return {h->type, h->bands, h->width, h->height, h->border};
}

void decode_and_check(std::span<const std::byte> bytes) {
  const TileShape shape = expected_shape(bytes);
  auto tile = decode_tile(bytes, "fuzz.rtile", shape);
  if (!tile) {
    FUZZ_CHECK(tile.error().message.starts_with("fuzz.rtile: "));
    return;
  }
  const TileHeader& h = tile->header;
  const Raster& r = tile->raster;
  FUZZ_CHECK(r.width() == h.width && r.height() == h.height);
  FUZZ_CHECK(r.type() == h.type && r.bands() == h.bands);
  FUZZ_CHECK(r.byte_size() ==
             r.pixel_count() * static_cast<size_t>(r.bands()) * sample_size(r.type()));
  // The lossless codecs give back every bit of what they decoded.
  if (h.codec == Codec::Zstd || h.codec == Codec::Png) {
    auto encoded = encode_tile(r, h.border, {h.codec});
    FUZZ_CHECK(encoded.has_value());
    auto again = decode_tile(*encoded, "again.rtile", shape);
    FUZZ_CHECK(again.has_value());
    FUZZ_CHECK(std::ranges::equal(again->raster.bytes(), r.bytes()));
  }
}

void put_u32(std::byte* at, uint32_t v) {
  std::memcpy(at, &v, sizeof v);
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  const auto bytes = std::as_bytes(std::span(data, size));
  decode_and_check(bytes);
  if (size < kTileHeaderSize) return 0;
  std::vector<std::byte> fixed(bytes.begin(), bytes.end());
  put_u32(fixed.data() + 72, crc32_of(std::span(fixed).subspan(kTileHeaderSize)));
  put_u32(fixed.data() + 76, crc32_of(std::span(fixed).first(76)));
  decode_and_check(fixed);
  return 0;
}
