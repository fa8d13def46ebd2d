#include "relief/tiles/level_index.h"

#include <gtest/gtest.h>

#include <cstring>
#include <string_view>
#include <vector>

#include "relief/tiles/tile_file.h"

namespace relief::tiles {

TEST(LevelIndex, RoundTripAndLookup) {
  LevelIndex index(10);
  index.add({{10, 517, 270}, 349.0f, 3100.0f, 1000, 5000});
  index.add({{10, 515, 271}, -20.0f, 1204.5f, 131072, 200000});
  index.add({{10, 1023, 0}, 1.0f, 2.0f, 1, 100});
  const auto bytes = index.serialize();
  auto back = LevelIndex::parse(bytes, "idx");
  ASSERT_TRUE(back) << back.error().message;
  EXPECT_EQ(back->size(), 3u);
  const IndexEntry* e = back->find({10, 515, 271});
  ASSERT_NE(e, nullptr);
  EXPECT_LE(e->min, -20.0f);
  EXPECT_GE(e->max, 1204.5f);
  EXPECT_EQ(e->valid_count, 131072u);
  EXPECT_EQ(back->find({10, 516, 271}), nullptr);
  EXPECT_EQ(back->total_bytes(), 205100u);
}

TEST(LevelIndex, GeometricErrorsRoundTripExactly) {
  LevelIndex index(4);
  index.add({{4, 3, 2}, 1.0f, 2.0f, 10, 100, 0.1f});
  index.add({{4, 5, 2}, 1.0f, 2.0f, 10, 100, 1234.5678f});
  index.set_error({4, 3, 2}, 17.25f);
  auto back = LevelIndex::parse(index.serialize(), "idx");
  ASSERT_TRUE(back) << back.error().message;
  EXPECT_EQ(back->find({4, 3, 2})->error, 17.25f);
  EXPECT_EQ(back->find({4, 5, 2})->error, 1234.5678f);
  // The error is covered by the checksum: a flipped bit is detected.
  auto bytes = index.serialize();
  bytes[bytes.size() - 5] ^= std::byte{1};
  EXPECT_FALSE(LevelIndex::parse(bytes, "idx"));
}

// A version 1 index (no errors) is refused with the way out; only `relief
// upgrade` reads it, as errors 0.
TEST(LevelIndex, VersionOneNamesTheUpgrade) {
  LevelIndex index(4);
  index.add({{4, 3, 2}, 1.0f, 2.0f, 10, 100, 5.0f});
  auto v2 = index.serialize();
  std::vector<std::byte> v1(v2.begin(), v2.end() - 4 - 4);  // drop the error and the CRC
  v1[8] = std::byte{1};
  const uint32_t crc = crc32_of(v1);
  v1.resize(v1.size() + 4);
  std::memcpy(v1.data() + v1.size() - 4, &crc, 4);
  auto refused = LevelIndex::parse(v1, "store/4/index.rli");
  ASSERT_FALSE(refused);
  EXPECT_EQ(refused.error().message,
            "store/4/index.rli: the store predates geometric errors (store format version 1); "
            "upgrade it with `relief upgrade store`");
  auto read = LevelIndex::parse_for_upgrade(v1, "idx");
  ASSERT_TRUE(read) << read.error().message;
  EXPECT_EQ(read->find({4, 3, 2})->error, 0.0f);
  EXPECT_EQ(read->find({4, 3, 2})->valid_count, 10u);
}

TEST(LevelIndex, EmptyLevel) {
  auto back = LevelIndex::parse(LevelIndex(3).serialize(), "idx");
  ASSERT_TRUE(back);
  EXPECT_EQ(back->size(), 0u);
  EXPECT_EQ(back->level(), 3);
}

TEST(LevelIndex, CorruptionIsDetected) {
  LevelIndex index(2);
  index.add({{2, 1, 1}, 0, 1, 1, 1});
  auto bytes = index.serialize();
  for (size_t i = 0; i < bytes.size(); ++i) {
    auto b = bytes;
    b[i] ^= std::byte{0x10};
    EXPECT_FALSE(LevelIndex::parse(b, "idx")) << i;
  }
  EXPECT_FALSE(LevelIndex::parse(std::span(bytes).first(bytes.size() - 1), "idx"));
}

// A count so large that the size check's sum wrapped around to the file's
// size: the bitmap loop then read 2^37 bytes of a 56-byte file (ASan report
// under fuzz/level_index.cpp on a version 1 index; the input is
// fuzz/regressions/level_index/). The same forgery for version 2's records.
TEST(LevelIndex, ForgedCountCannotWrapTheSizeCheck) {
  std::vector<std::byte> b;
  auto put = [&b](auto v) {
    const auto* p = reinterpret_cast<const std::byte*>(&v);
    b.insert(b.end(), p, p + sizeof v);
  };
  for (char c : std::string_view("RELIEFI\0", 8)) put(c);
  put(uint16_t{2});
  put(uint16_t{20});
  put(uint32_t{0x66259756});  // x0: makes the CRC 0, so no bit of the file is set past the header
  put(uint32_t{0});
  put(uint32_t{1} << 20);  // columns and rows: a bitmap of 2^37 bytes
  put(uint32_t{1} << 20);
  put(uint64_t{0x1999999800000001});  // count * 20 + 2^37 wraps to 20
  b.resize(b.size() + 20);
  put(crc32_of(b));
  ASSERT_EQ(b.size(), 60u);
  ASSERT_EQ(crc32_of(std::span(b).first(56)), 0u);
  auto index = LevelIndex::parse(b, "idx");
  ASSERT_FALSE(index);
  EXPECT_NE(index.error().message.find("truncated or inconsistent"), std::string::npos)
      << index.error().message;
}

}  // namespace relief::tiles
