#include "relief/tiles/codec.h"

#include <gtest/gtest.h>

#include <cstring>
#include <utility>

#include "test_rasters.h"

namespace relief::tiles {
namespace {

bool same_bits(const Raster& a, const Raster& b) {
  return a.byte_size() == b.byte_size() &&
         std::memcmp(a.bytes().data(), b.bytes().data(), a.byte_size()) == 0;
}

TEST(Codec, ZstdIsBitExactForFloatsWithNaN) {
  const Raster r = testing::terrain(530, 274);
  auto bytes = encode(r, {Codec::Zstd});
  ASSERT_TRUE(bytes) << bytes.error().message;
  EXPECT_LT(bytes->size(), r.byte_size());
  auto back = decode(Codec::Zstd, *bytes, SampleType::Float32, 1, 530, 274);
  ASSERT_TRUE(back) << back.error().message;
  EXPECT_TRUE(same_bits(r, *back));
}

TEST(Codec, ZstdIsExactForImagery) {
  const Raster r = testing::image(100, 60);
  auto bytes = encode(r, {Codec::Zstd});
  ASSERT_TRUE(bytes);
  auto back = decode(Codec::Zstd, *bytes, SampleType::UInt8, 4, 100, 60);
  ASSERT_TRUE(back);
  EXPECT_TRUE(same_bits(r, *back));
}

TEST(Codec, LercRespectsMaxErrorAndKeepsNoData) {
  const Raster r = testing::terrain(530, 274);
  for (double max_error : {0.01, 0.5, 2.0}) {
    auto bytes = encode(r, {Codec::Lerc, max_error});
    ASSERT_TRUE(bytes) << bytes.error().message;
    auto back = decode(Codec::Lerc, *bytes, SampleType::Float32, 1, 530, 274);
    ASSERT_TRUE(back) << back.error().message;
    auto a = r.f32();
    auto b = std::as_const(*back).f32();
    for (size_t i = 0; i < a.size(); ++i) {
      ASSERT_EQ(std::isnan(a[i]), std::isnan(b[i])) << i;
      if (!std::isnan(a[i])) {
        ASSERT_LE(std::abs(a[i] - b[i]), max_error * 1.0001) << i;
      }
    }
  }
}

TEST(Codec, PngIsLossless) {
  const Raster r = testing::image(64, 32);
  auto bytes = encode(r, {Codec::Png});
  ASSERT_TRUE(bytes);
  auto back = decode(Codec::Png, *bytes, SampleType::UInt8, 4, 64, 32);
  ASSERT_TRUE(back);
  EXPECT_TRUE(same_bits(r, *back));
}

TEST(Codec, LossyImageCodecsKeepAlphaAndApproximateColour) {
  const Raster r = testing::image(64, 32);
  for (Codec c : {Codec::Jpeg, Codec::Webp}) {
    auto bytes = encode(r, {c, 0, 95});
    ASSERT_TRUE(bytes) << to_string(c);
    auto back = decode(c, *bytes, SampleType::UInt8, 4, 64, 32);
    ASSERT_TRUE(back) << back.error().message;
    double err = 0;
    int n = 0;
    for (size_t p = 0; p < r.pixel_count(); ++p) {
      ASSERT_EQ(r.u8()[p * 4 + 3], back->u8()[p * 4 + 3]) << to_string(c);
      if (r.u8()[p * 4 + 3] == 0) continue;
      for (size_t b = 0; b < 3; ++b) err += std::abs(r.u8()[p * 4 + b] - back->u8()[p * 4 + b]);
      n += 3;
    }
    EXPECT_LT(err / n, 6.0) << to_string(c);
  }
}

TEST(Codec, RejectsMismatchedTypes) {
  EXPECT_FALSE(encode(testing::image(8, 8), {Codec::Lerc, 0.1}));
  EXPECT_FALSE(encode(testing::terrain(8, 8), {Codec::Png}));
}

TEST(Codec, CorruptPayloadsAreErrorsNotCrashes) {
  const Raster f = testing::terrain(64, 32);
  const Raster img = testing::image(64, 32);
  struct Case {
    Codec codec;
    const Raster* raster;
  };
  for (auto [codec, raster] : {Case{Codec::Zstd, &f}, Case{Codec::Lerc, &f}, Case{Codec::Png, &img},
                               Case{Codec::Jpeg, &img}, Case{Codec::Webp, &img}}) {
    auto bytes = encode(*raster, {codec, 0.1, 90});
    ASSERT_TRUE(bytes);
    const int bands = raster->bands();
    // Truncations and flipped bytes.
    for (size_t cut : {size_t{0}, size_t{3}, bytes->size() / 2, bytes->size() - 1}) {
      std::span<const std::byte> part(bytes->data(), cut);
      (void)decode(codec, part, raster->type(), bands, 64, 32);
    }
    auto garbage = *bytes;
    for (size_t i = 0; i < garbage.size(); i += 7) garbage[i] ^= std::byte{0x5A};
    (void)decode(codec, garbage, raster->type(), bands, 64, 32);
    // Wrong dimensions are always detected.
    EXPECT_FALSE(decode(codec, *bytes, raster->type(), bands, 63, 32)) << to_string(codec);
  }
}

}  // namespace
}  // namespace relief::tiles
