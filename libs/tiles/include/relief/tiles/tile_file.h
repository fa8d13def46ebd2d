#pragma once
// One tile file: an 80-byte little-endian header followed by the codec payload.
// Layout (see docs/store-format.md):
//   0  char[8]  magic "RELIEFT\0"      40 f64  mean of valid interior samples
//   8  u16      format version (1)     48 f64  standard deviation
//  10  u8       codec                  56 u64  valid interior samples
//  11  u8       sample type            64 u64  payload size in bytes
//  12  u8       bands                  72 u32  CRC-32 of the payload
//  13  u8       reserved (0)           76 u32  CRC-32 of bytes 0..75
//  14  u16      width incl. border
//  16  u16      height incl. border
//  18  u16      border
//  20  u32      reserved (0)
//  24  f64      min of valid interior samples (lower bound if lossy)
//  32  f64      max of valid interior samples (upper bound if lossy)
#include <cstddef>
#include <cstdint>
#include <span>
#include <string>
#include <vector>

#include "relief/base/result.h"
#include "relief/tiles/codec.h"
#include "relief/tiles/raster.h"

namespace relief::tiles {

inline constexpr uint16_t kTileFormatVersion = 1;
inline constexpr size_t kTileHeaderSize = 80;

struct TileHeader {
  uint16_t version = kTileFormatVersion;
  Codec codec = Codec::Zstd;
  SampleType type = SampleType::Float32;
  uint8_t bands = 1;
  uint16_t width = 0, height = 0, border = 0;
  SampleStats stats;  // of the interior (border excluded)
  uint64_t payload_size = 0;
  uint32_t payload_crc = 0;

  int interior_width() const { return width - 2 * border; }
  int interior_height() const { return height - 2 * border; }
};

struct Tile {
  TileHeader header;
  Raster raster;  // width x height, border included
};

// The shape every tile of a store has (Store::tile_shape, from the manifest).
// Tile files are untrusted input: a header is checked against the expected
// shape before anything is allocated or decoded, so a forged size is an
// error, not a 17 GB allocation.
struct TileShape {
  SampleType type = SampleType::Float32;
  int bands = 1;
  int width = 0, height = 0;  // border included
  int border = 0;

  size_t raster_bytes() const;
  std::string to_string() const;  // "530x274 (border 9) float32 x1"
};

// The largest file a tile of this shape can be: the header plus the worst case
// of every codec (twice the raw samples covers them all) plus slack. Remote
// sources cap a tile's download by it.
uint64_t max_tile_file_bytes(const TileShape& shape);

// Encodes a bordered raster; statistics are computed over the interior.
Result<std::vector<std::byte>> encode_tile(const Raster& bordered, int border,
                                           const CodecOptions& options);
// Parses and checks the header alone (magic, version, header CRC, sizes).
// `name` is used in error messages.
Result<TileHeader> parse_tile_header(std::span<const std::byte> bytes, const std::string& name);
// Whether the header describes a tile of the expected shape.
Status check_tile_shape(const TileHeader& header, const TileShape& expected,
                        const std::string& name);
// Parses the header, checks it against `expected` (before allocating), checks
// the payload CRC and decodes.
Result<Tile> decode_tile(std::span<const std::byte> bytes, const std::string& name,
                         const TileShape& expected);

uint32_t crc32_of(std::span<const std::byte> bytes);

}  // namespace relief::tiles
