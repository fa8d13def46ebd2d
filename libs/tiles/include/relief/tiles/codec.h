#pragma once
// Payload codecs of tile files. Each codec turns a Raster into bytes and back;
// decoding validates everything it reads, so corrupt input is an error, never
// a crash.
#include <cstdint>
#include <span>
#include <string_view>
#include <vector>

#include "relief/base/result.h"
#include "relief/tiles/raster.h"

namespace relief::tiles {

enum class Codec : uint8_t {
  Zstd = 1,  // lossless: horizontal predictor + byte planes + zstd (any sample type)
  Lerc = 2,  // Float32 with a maximum absolute error per sample
  Png = 3,   // UInt8 RGBA, lossless
  Jpeg = 4,  // UInt8 RGB lossy + lossless alpha plane
  Webp = 5,  // UInt8 RGBA lossy, lossless alpha
};

std::string_view to_string(Codec c);
Result<Codec> codec_from_string(std::string_view s);
bool codec_supports(Codec c, SampleType t);

struct CodecOptions {
  Codec codec = Codec::Zstd;
  double max_error = 0.0;  // Lerc: largest allowed |decoded - original|
  int quality = 90;        // Jpeg, Webp: 1..100
  int zstd_level = 3;
};

Result<std::vector<std::byte>> encode(const Raster& raster, const CodecOptions& options);
// `type`, `bands`, `width`, `height` come from the tile header and are checked
// against what the payload holds.
Result<Raster> decode(Codec codec, std::span<const std::byte> payload, SampleType type, int bands,
                      int width, int height);

// Codec-specific halves, one translation unit each.
namespace detail {
Result<std::vector<std::byte>> encode_zstd(const Raster& r, int level);
Result<Raster> decode_zstd(std::span<const std::byte> p, SampleType t, int bands, int w, int h);
Result<std::vector<std::byte>> encode_lerc(const Raster& r, double max_error);
Result<Raster> decode_lerc(std::span<const std::byte> p, int w, int h);
Result<std::vector<std::byte>> encode_png(const Raster& r);
Result<Raster> decode_png(std::span<const std::byte> p, int w, int h);
Result<std::vector<std::byte>> encode_jpeg(const Raster& r, int quality);
Result<Raster> decode_jpeg(std::span<const std::byte> p, int w, int h);
Result<std::vector<std::byte>> encode_webp(const Raster& r, int quality);
Result<Raster> decode_webp(std::span<const std::byte> p, int w, int h);
}  // namespace detail

}  // namespace relief::tiles
