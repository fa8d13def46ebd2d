// Tile files are untrusted (a copied store, a remote server): a header whose
// sizes were forged, checksum recomputed, is refused against the store's tile
// shape before anything is allocated, and a codec payload whose own sizes
// disagree with its header is refused too.
#include <gtest/gtest.h>
#include <sys/stat.h>
#include <unistd.h>

#include <cmath>
#include <cstring>

#include <fmt/format.h>

#include "relief/base/memory_use.h"
#include "relief/base/parallel.h"
#include "relief/base/progress.h"
#include "relief/base/units.h"
#include "relief/tiles/store.h"
#include "relief/tiles/store_layout.h"
#include "relief/tiles/tile_file.h"
#include "relief/tiles/verify.h"
#include "test_rasters.h"

namespace relief::tiles {
namespace {
namespace fs = std::filesystem;

constexpr uint64_t kMiB = uint64_t{1} << 20;

// The header field at `offset` replaced, and the header checksum recomputed
// as a forger would.
template <class T>
std::vector<std::byte> forged(std::vector<std::byte> bytes, size_t offset, T value) {
  std::memcpy(bytes.data() + offset, &value, sizeof value);
  const uint32_t crc = crc32_of({bytes.data(), 76});
  std::memcpy(bytes.data() + 76, &crc, sizeof crc);
  return bytes;
}

std::vector<std::byte> huge(std::vector<std::byte> bytes) {
  return forged<uint16_t>(forged<uint16_t>(std::move(bytes), 14, 65535), 16, 65535);
}

struct Case {
  CodecOptions codec;
  SampleType type;
};
const Case kCases[] = {
    {{Codec::Zstd}, SampleType::Float32}, {{Codec::Lerc, 0.5}, SampleType::Float32},
    {{Codec::Zstd}, SampleType::UInt8},   {{Codec::Png}, SampleType::UInt8},
    {{Codec::Jpeg}, SampleType::UInt8},   {{Codec::Webp}, SampleType::UInt8},
};

Raster raster_of(SampleType type, int w, int h) {
  return type == SampleType::Float32 ? testing::terrain(w, h) : testing::image(w, h);
}
TileShape shape_of(SampleType type, int w, int h, int border) {
  return {type, type == SampleType::Float32 ? 1 : 4, w, h, border};
}

TEST(ForgedTile, HugeHeaderSizesAreRefusedBeforeDecodingForEveryCodec) {
  const uint64_t rss_before = resident_set_bytes();
  for (const Case& c : kCases) {
    const std::string what(to_string(c.codec.codec));
    const TileShape expected = shape_of(c.type, 64, 32, 4);
    auto bytes = encode_tile(raster_of(c.type, 64, 32), 4, c.codec);
    ASSERT_TRUE(bytes) << what;
    ASSERT_TRUE(decode_tile(*bytes, "t.rtile", expected)) << what;
    auto t = decode_tile(huge(*bytes), "x/y.rtile", expected);
    ASSERT_FALSE(t) << what;
    EXPECT_EQ(t.error().message,
              fmt::format("x/y.rtile: tile header says 65535x65535 (border 4) {} x{}, the store's "
                          "tiles are 64x32 (border 4) {} x{}",
                          to_string(c.type), expected.bands, to_string(c.type), expected.bands));
  }
  // 65535 x 65535 float samples would be 17 GB: nothing of the kind was allocated.
  const uint64_t rss_after = resident_set_bytes();
  EXPECT_LT(rss_after, rss_before + 64 * kMiB);
}

TEST(ForgedTile, EveryHeaderSizeIsCheckedAgainstTheStore) {
  const TileShape expected = shape_of(SampleType::Float32, 64, 32, 4);
  const auto bytes = *encode_tile(testing::terrain(64, 32), 4, {Codec::Zstd});
  auto refused = [&](const std::vector<std::byte>& b, const std::string& says) {
    auto t = decode_tile(b, "t.rtile", expected);
    ASSERT_FALSE(t) << says;
    EXPECT_NE(t.error().message.find("tile header says " + says), std::string::npos)
        << t.error().message;
  };
  refused(forged<uint16_t>(bytes, 14, 66), "66x32 (border 4) float32 x1");
  refused(forged<uint16_t>(bytes, 16, 30), "64x30 (border 4) float32 x1");
  refused(forged<uint16_t>(bytes, 18, 5), "64x32 (border 5) float32 x1");
  refused(forged<uint8_t>(bytes, 12, 4), "64x32 (border 4) float32 x4");
  refused(forged<uint8_t>(bytes, 11, 2), "64x32 (border 4) uint8 x1");
}

// A header that agrees with the store over a payload that does not: each
// codec's own sizes (PNG IHDR, JPEG SOF, WebP VP8, LERC header, zstd frame
// content size) are checked against the header before decoding into it.
TEST(ForgedTile, CodecSizesMustAgreeWithTheHeader) {
  for (const Case& c : kCases) {
    const std::string what(to_string(c.codec.codec));
    auto bigger = encode_tile(raster_of(c.type, 72, 40), 4, c.codec);
    ASSERT_TRUE(bigger) << what;
    // The header now claims the store's 64 x 32, the payload still holds 72 x 40.
    auto lying = forged<uint16_t>(forged<uint16_t>(*bigger, 14, 64), 16, 32);
    auto t = decode_tile(lying, "t.rtile", shape_of(c.type, 64, 32, 4));
    ASSERT_FALSE(t) << what;
    EXPECT_NE(t.error().message.find(what), std::string::npos) << t.error().message;
  }
}

// A zstd frame header claiming 16 GiB of content, nothing after it.
TEST(ForgedTile, ZstdFrameClaimingHugeContentIsRefused) {
  std::vector<std::byte> frame = {std::byte{0x28}, std::byte{0xB5}, std::byte{0x2F},
                                  std::byte{0xFD}, std::byte{0xC0},  // 8-byte content size
                                  std::byte{0x58}};                  // window 2^21
  const uint64_t claimed = uint64_t{16} << 30;
  for (int i = 0; i < 8; ++i) frame.push_back(static_cast<std::byte>((claimed >> (8 * i)) & 0xFF));
  const uint64_t rss_before = resident_set_bytes();
  auto r = decode(Codec::Zstd, frame, SampleType::Float32, 1, 64, 32);
  ASSERT_FALSE(r);
  EXPECT_NE(r.error().message.find("wrong size"), std::string::npos) << r.error().message;
  EXPECT_LT(resident_set_bytes(), rss_before + 64 * kMiB);
}

TEST(ForgedTile, TheLargestTileFileCoversEveryCodecsWorstCase) {
  // Noise compresses worst; every codec's file stays within the bound.
  for (const Case& c : kCases) {
    Raster r = raster_of(c.type, 64, 32);
    uint32_t x = 12345;
    for (auto& b : r.bytes()) {
      x = x * 1664525u + 1013904223u;
      b = static_cast<std::byte>(x >> 24);
    }
    if (c.type == SampleType::Float32) {
      for (float& v : r.f32()) v = std::isfinite(v) ? v : 1.0f;
    }
    auto bytes = encode_tile(r, 4, {c.codec.codec, 0.0, 100});
    ASSERT_TRUE(bytes) << to_string(c.codec.codec);
    EXPECT_LE(bytes->size(), max_tile_file_bytes(shape_of(c.type, 64, 32, 4)));
  }
  EXPECT_EQ(max_tile_file_bytes(shape_of(SampleType::Float32, 530, 274, 9)),
            80 + 2 * 530 * 274 * 4 + kMiB);
}

// A one-tile store of 64 x 32 tiles with a border of 8 under `root`, its tile
// file `tile` (a real tile, or forged); returns the tile's key.
geo::TileKey one_tile_store(const fs::path& root, const std::vector<std::byte>& tile) {
  fs::remove_all(root);
  const geo::TileKey key{0, 0, 0};
  auto bytes = *encode_tile(testing::terrain(80, 48), 8, {Codec::Zstd});
  const TileHeader h = *parse_tile_header(bytes, "t");
  EXPECT_TRUE(write_tile_file(root, key, tile.empty() ? bytes : tile));
  LevelIndex index(0);
  const IndexEntry entry = index_entry_for(key, h, bytes.size());
  index.add(entry);
  EXPECT_TRUE(write_level_index(root, index));
  Manifest m;
  m.stats = h.stats;  // verify checks the statistics against the index
  m.tile_log2_height = 5;
  m.border = 8;
  m.extent = {-180, -90, 180, 90};
  EXPECT_TRUE(write_manifest(root, m));
  return key;
}

fs::path scratch_root(const std::string& name) {
  return fs::temp_directory_path() / fmt::format("relief_{}_{}", name, ::getpid());
}

// A store on disk whose tile was forged: reading and verifying it fail with
// the tile's path, without allocating for the forged size.
TEST(ForgedTile, StoresRefuseForgedTilesWhenReadingAndVerifying) {
  const fs::path root = scratch_root("forged");
  const geo::TileKey key =
      one_tile_store(root, huge(*encode_tile(testing::terrain(80, 48), 8, {Codec::Zstd})));
  const uint64_t rss_before = resident_set_bytes();
  auto store = Store::open(root);
  ASSERT_TRUE(store) << store.error().message;
  auto tile = store->read_tile(key);
  ASSERT_FALSE(tile);
  const std::string path = (root / tile_relative_path(key)).string();
  EXPECT_EQ(tile.error().message,
            path +
                ": tile header says 65535x65535 (border 8) float32 x1, the store's tiles are "
                "80x48 (border 8) float32 x1");
  InlineExecutor executor;
  NullProgress progress;
  const VerifyReport report = verify_store(root, executor, progress);
  ASSERT_EQ(report.problems.size(), 1u);
  EXPECT_EQ(report.problems[0], tile.error().message);
  EXPECT_LT(resident_set_bytes(), rss_before + 64 * kMiB);
  fs::remove_all(root);
}

// A tile file far larger than any tile of the store can be (sparse: it costs
// no disk), or a FIFO that would block a reader forever: errors before reading.
TEST(ForgedTile, HugeOrSpecialTileFilesAreNotRead) {
  const fs::path root = scratch_root("huge_file");
  const geo::TileKey key = one_tile_store(root, {});
  const fs::path path = root / tile_relative_path(key);
  auto store = Store::open(root);
  ASSERT_TRUE(store) << store.error().message;
  ASSERT_TRUE(store->read_tile(key));
  const uint64_t cap = max_tile_file_bytes(store->tile_shape());

  fs::resize_file(path, uint64_t{1} << 30);
  const uint64_t rss_before = resident_set_bytes();
  auto huge_file = store->read_tile(key);
  ASSERT_FALSE(huge_file);
  EXPECT_EQ(huge_file.error().message,
            fmt::format("{}: 1073741824 bytes, more than {}, the most this file can hold",
                        path.string(), format_bytes(cap)));
  EXPECT_LT(resident_set_bytes(), rss_before + 64 * kMiB);

  fs::remove(path);
  ASSERT_EQ(::mkfifo(path.c_str(), 0600), 0);
  auto fifo = store->read_tile(key);
  ASSERT_FALSE(fifo);
  EXPECT_EQ(fifo.error().message, path.string() + ": is a FIFO, not a regular file");
  fs::remove_all(root);
}

}  // namespace
}  // namespace relief::tiles
