#include "relief/tiles/tile_file.h"

#include <gtest/gtest.h>

#include "test_rasters.h"

namespace relief::tiles {
namespace {

TEST(TileFile, RoundTripWithInteriorStatistics) {
  Raster r = testing::terrain(530, 274, 5, false);
  r.f32()[0] = -99999.0f;  // in the border: must not count in the statistics
  auto bytes = encode_tile(r, 9, {Codec::Zstd});
  ASSERT_TRUE(bytes);
  auto tile = decode_tile(*bytes, "t", {SampleType::Float32, 1, 530, 274, 9});
  ASSERT_TRUE(tile) << tile.error().message;
  EXPECT_EQ(tile->header.width, 530);
  EXPECT_EQ(tile->header.interior_width(), 512);
  EXPECT_EQ(tile->header.interior_height(), 256);
  EXPECT_EQ(tile->header.stats.valid_count, 512u * 256u);
  EXPECT_GT(tile->header.stats.min, 0);
  const SampleStats s = r.stats(9, 9, 512, 256);
  EXPECT_DOUBLE_EQ(tile->header.stats.max, s.max);
  EXPECT_DOUBLE_EQ(tile->header.stats.mean, s.mean);
}

TEST(TileFile, LercBoundsCoverTheDecodedValues) {
  const Raster r = testing::terrain(530, 274);
  auto bytes = encode_tile(r, 9, {Codec::Lerc, 1.0});
  ASSERT_TRUE(bytes);
  auto tile = decode_tile(*bytes, "t", {SampleType::Float32, 1, 530, 274, 9});
  ASSERT_TRUE(tile);
  const SampleStats s = tile->raster.stats(9, 9, 512, 256);
  EXPECT_LE(tile->header.stats.min, s.min);
  EXPECT_GE(tile->header.stats.max, s.max);
}

TEST(TileFile, DetectsEveryKindOfDamage) {
  auto bytes = *encode_tile(testing::terrain(64, 32), 4, {Codec::Zstd});
  auto expect_error = [](std::vector<std::byte> b, const std::string& what) {
    auto t = decode_tile(b, "x/y.rtile", {SampleType::Float32, 1, 64, 32, 4});
    ASSERT_FALSE(t) << what;
    EXPECT_NE(t.error().message.find("x/y.rtile"), std::string::npos);
    EXPECT_NE(t.error().message.find(what), std::string::npos) << t.error().message;
  };
  expect_error({bytes.begin(), bytes.begin() + 40}, "truncated");
  expect_error({bytes.begin(), bytes.end() - 5}, "truncated");
  auto flipped_payload = bytes;
  flipped_payload[kTileHeaderSize + 10] ^= std::byte{1};
  expect_error(flipped_payload, "payload checksum");
  auto flipped_header = bytes;
  flipped_header[30] ^= std::byte{1};
  expect_error(flipped_header, "header checksum");
  auto not_tile = bytes;
  not_tile[0] = std::byte{'X'};
  expect_error(not_tile, "not a relief tile");
  expect_error({}, "truncated");
}

}  // namespace
}  // namespace relief::tiles
