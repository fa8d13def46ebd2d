#include "relief/tiles/codec.h"

#include <fmt/format.h>

namespace relief::tiles {

std::string_view to_string(Codec c) {
  switch (c) {
    case Codec::Zstd:
      return "zstd";
    case Codec::Lerc:
      return "lerc";
    case Codec::Png:
      return "png";
    case Codec::Jpeg:
      return "jpeg";
    case Codec::Webp:
      return "webp";
  }
  return "?";
}

Result<Codec> codec_from_string(std::string_view s) {
  for (Codec c : {Codec::Zstd, Codec::Lerc, Codec::Png, Codec::Jpeg, Codec::Webp}) {
    if (s == to_string(c)) return c;
  }
  return fail(fmt::format("unknown codec '{}' (zstd, lerc, png, jpeg, webp)", s));
}

bool codec_supports(Codec c, SampleType t) {
  switch (c) {
    case Codec::Zstd:
      return true;
    case Codec::Lerc:
      return t == SampleType::Float32;
    case Codec::Png:
    case Codec::Jpeg:
    case Codec::Webp:
      return t == SampleType::UInt8;
  }
  return false;
}

Result<std::vector<std::byte>> encode(const Raster& raster, const CodecOptions& o) {
  if (!codec_supports(o.codec, raster.type())) {
    return fail(fmt::format("codec {} cannot store {} samples", to_string(o.codec),
                            to_string(raster.type())));
  }
  switch (o.codec) {
    case Codec::Zstd:
      return detail::encode_zstd(raster, o.zstd_level);
    case Codec::Lerc:
      return detail::encode_lerc(raster, o.max_error);
    case Codec::Png:
      return detail::encode_png(raster);
    case Codec::Jpeg:
      return detail::encode_jpeg(raster, o.quality);
    case Codec::Webp:
      return detail::encode_webp(raster, o.quality);
  }
  return fail("unknown codec");
}

Result<Raster> decode(Codec codec, std::span<const std::byte> payload, SampleType type, int bands,
                      int width, int height) {
  if (!codec_supports(codec, type)) {
    return fail(
        fmt::format("codec {} does not hold {} samples", to_string(codec), to_string(type)));
  }
  const int expected_bands = type == SampleType::Float32 ? 1 : 4;
  if (bands != expected_bands || width <= 0 || height <= 0) {
    return fail(fmt::format("bad raster shape {}x{}x{}", width, height, bands));
  }
  switch (codec) {
    case Codec::Zstd:
      return detail::decode_zstd(payload, type, bands, width, height);
    case Codec::Lerc:
      return detail::decode_lerc(payload, width, height);
    case Codec::Png:
      return detail::decode_png(payload, width, height);
    case Codec::Jpeg:
      return detail::decode_jpeg(payload, width, height);
    case Codec::Webp:
      return detail::decode_webp(payload, width, height);
  }
  return fail("unknown codec");
}

}  // namespace relief::tiles
