#include "relief/tiles/tile_file.h"

#include <zlib.h>

#include <algorithm>
#include <bit>
#include <cmath>
#include <cstring>

#include <fmt/format.h>

namespace relief::tiles {
namespace {

constexpr char kMagic[8] = {'R', 'E', 'L', 'I', 'E', 'F', 'T', '\0'};
static_assert(std::endian::native == std::endian::little, "tile files are little-endian");

template <class T>
void put(std::byte* at, T v) {
  std::memcpy(at, &v, sizeof v);
}
template <class T>
T get(const std::byte* at) {
  T v;
  std::memcpy(&v, at, sizeof v);
  return v;
}

}  // namespace

uint32_t crc32_of(std::span<const std::byte> bytes) {
  uLong crc = crc32(0L, Z_NULL, 0);
  size_t done = 0;
  while (done < bytes.size()) {
    const auto n = static_cast<uInt>(std::min<size_t>(bytes.size() - done, 1u << 30));
    crc = crc32(crc, reinterpret_cast<const Bytef*>(bytes.data() + done), n);
    done += n;
  }
  return static_cast<uint32_t>(crc);
}

Result<std::vector<std::byte>> encode_tile(const Raster& r, int border,
                                           const CodecOptions& options) {
  if (r.width() > 65535 || r.height() > 65535 || 2 * border >= r.width() ||
      2 * border >= r.height()) {
    return fail(fmt::format("tile of {}x{} with border {} cannot be stored", r.width(), r.height(),
                            border));
  }
  auto payload = encode(r, options);
  if (!payload) return std::unexpected(payload.error());
  TileHeader h;
  h.codec = options.codec;
  h.type = r.type();
  h.bands = static_cast<uint8_t>(r.bands());
  h.width = static_cast<uint16_t>(r.width());
  h.height = static_cast<uint16_t>(r.height());
  h.border = static_cast<uint16_t>(border);
  h.stats = r.stats(border, border, r.width() - 2 * border, r.height() - 2 * border);
  if (options.codec == Codec::Lerc && h.stats.valid_count > 0) {
    h.stats.min -= options.max_error;  // bounds must hold for the decoded samples
    h.stats.max += options.max_error;
  }
  h.payload_size = payload->size();
  h.payload_crc = crc32_of(*payload);

  std::vector<std::byte> out(kTileHeaderSize + payload->size());
  std::byte* p = out.data();
  std::memcpy(p, kMagic, 8);
  put<uint16_t>(p + 8, h.version);
  put<uint8_t>(p + 10, static_cast<uint8_t>(h.codec));
  put<uint8_t>(p + 11, static_cast<uint8_t>(h.type));
  put<uint8_t>(p + 12, h.bands);
  put<uint8_t>(p + 13, 0);
  put<uint16_t>(p + 14, h.width);
  put<uint16_t>(p + 16, h.height);
  put<uint16_t>(p + 18, h.border);
  put<uint32_t>(p + 20, 0);
  put<double>(p + 24, h.stats.min);
  put<double>(p + 32, h.stats.max);
  put<double>(p + 40, h.stats.mean);
  put<double>(p + 48, h.stats.stddev);
  put<uint64_t>(p + 56, h.stats.valid_count);
  put<uint64_t>(p + 64, h.payload_size);
  put<uint32_t>(p + 72, h.payload_crc);
  put<uint32_t>(p + 76, crc32_of({p, 76}));
  std::memcpy(p + kTileHeaderSize, payload->data(), payload->size());
  return out;
}

Result<TileHeader> parse_tile_header(std::span<const std::byte> bytes, const std::string& name) {
  if (bytes.size() < kTileHeaderSize) {
    return fail(fmt::format("{}: truncated tile ({} bytes, header needs {})", name, bytes.size(),
                            kTileHeaderSize));
  }
  const std::byte* p = bytes.data();
  if (std::memcmp(p, kMagic, 8) != 0) return fail(fmt::format("{}: not a relief tile", name));
  if (get<uint32_t>(p + 76) != crc32_of({p, 76})) {
    return fail(fmt::format("{}: tile header checksum mismatch", name));
  }
  TileHeader h;
  h.version = get<uint16_t>(p + 8);
  if (h.version != kTileFormatVersion) {
    return fail(fmt::format("{}: unsupported tile format version {}", name, h.version));
  }
  h.codec = static_cast<Codec>(get<uint8_t>(p + 10));
  h.type = static_cast<SampleType>(get<uint8_t>(p + 11));
  h.bands = get<uint8_t>(p + 12);
  h.width = get<uint16_t>(p + 14);
  h.height = get<uint16_t>(p + 16);
  h.border = get<uint16_t>(p + 18);
  h.stats.min = get<double>(p + 24);
  h.stats.max = get<double>(p + 32);
  h.stats.mean = get<double>(p + 40);
  h.stats.stddev = get<double>(p + 48);
  h.stats.valid_count = get<uint64_t>(p + 56);
  h.payload_size = get<uint64_t>(p + 64);
  h.payload_crc = get<uint32_t>(p + 72);
  if (h.type != SampleType::Float32 && h.type != SampleType::UInt8) {
    return fail(fmt::format("{}: unknown sample type {}", name, static_cast<int>(h.type)));
  }
  if (!codec_supports(h.codec, h.type)) {
    return fail(fmt::format("{}: unknown codec {}", name, static_cast<int>(h.codec)));
  }
  if (2 * h.border >= h.width || 2 * h.border >= h.height) {
    return fail(
        fmt::format("{}: bad tile shape {}x{} border {}", name, h.width, h.height, h.border));
  }
  // Readers bound heights and colours by these (the level index is made of
  // them): a NaN or an infinity, or a min above the max, is a forged or
  // damaged header.
  // The mean, a sum divided, may round past min or max by an ulp or so.
  const SampleStats& st = h.stats;
  const double slack = 1e-9 * std::max({1.0, std::abs(st.min), std::abs(st.max)});
  if (st.valid_count > 0 &&
      !(std::isfinite(st.min) && std::isfinite(st.max) && std::isfinite(st.stddev) &&
        st.min <= st.max && st.mean >= st.min - slack && st.mean <= st.max + slack &&
        st.stddev >= 0)) {
    return fail(
        fmt::format("{}: tile header statistics min {} max {} mean {} std {} are not finite with "
                    "min <= mean <= max",
                    name, st.min, st.max, st.mean, st.stddev));
  }
  if (h.payload_size != bytes.size() - kTileHeaderSize) {
    return fail(fmt::format("{}: truncated tile (payload {} bytes, header says {})", name,
                            bytes.size() - kTileHeaderSize, h.payload_size));
  }
  return h;
}

size_t TileShape::raster_bytes() const {
  return static_cast<size_t>(width) * static_cast<size_t>(height) * static_cast<size_t>(bands) *
         sample_size(type);
}

std::string TileShape::to_string() const {
  return fmt::format("{}x{} (border {}) {} x{}", width, height, border, tiles::to_string(type),
                     bands);
}

uint64_t max_tile_file_bytes(const TileShape& shape) {
  return kTileHeaderSize + 2 * uint64_t{shape.raster_bytes()} + (uint64_t{1} << 20);
}

Status check_tile_shape(const TileHeader& h, const TileShape& expected, const std::string& name) {
  const TileShape got{h.type, h.bands, h.width, h.height, h.border};
  if (got.type != expected.type || got.bands != expected.bands || got.width != expected.width ||
      got.height != expected.height || got.border != expected.border) {
    return fail(fmt::format("{}: tile header says {}, the store's tiles are {}", name,
                            got.to_string(), expected.to_string()));
  }
  return {};
}

Result<Tile> decode_tile(std::span<const std::byte> bytes, const std::string& name,
                         const TileShape& expected) {
  auto header = parse_tile_header(bytes, name);
  if (!header) return std::unexpected(header.error());
  RELIEF_CHECK(check_tile_shape(*header, expected, name));
  auto payload = bytes.subspan(kTileHeaderSize);
  if (crc32_of(payload) != header->payload_crc) {
    return fail(fmt::format("{}: tile payload checksum mismatch", name));
  }
  auto raster =
      decode(header->codec, payload, header->type, header->bands, header->width, header->height);
  if (!raster) return fail(fmt::format("{}: {}", name, raster.error().message));
  return Tile{*header, std::move(*raster)};
}

}  // namespace relief::tiles
