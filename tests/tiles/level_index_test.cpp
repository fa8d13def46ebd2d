#include "relief/tiles/level_index.h"

#include <gtest/gtest.h>

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
// under fuzz/level_index.cpp; the input is fuzz/regressions/level_index/).
TEST(LevelIndex, ForgedCountCannotWrapTheSizeCheck) {
  std::vector<std::byte> b;
  auto put = [&b](auto v) {
    const auto* p = reinterpret_cast<const std::byte*>(&v);
    b.insert(b.end(), p, p + sizeof v);
  };
  for (char c : std::string_view("RELIEFI\0", 8)) put(c);
  put(uint16_t{1});
  put(uint16_t{20});
  put(uint32_t{0xbb8bf317});  // x0: makes the CRC 0, so no bit of the file is set past the header
  put(uint32_t{0});
  put(uint32_t{1} << 20);  // columns and rows: a bitmap of 2^37 bytes
  put(uint32_t{1} << 20);
  put((uint64_t{1} << 60) + 1 - (uint64_t{1} << 33));  // count * 16 + 2^37 wraps to 16
  b.resize(b.size() + 16);
  put(crc32_of(b));
  ASSERT_EQ(b.size(), 56u);
  ASSERT_EQ(crc32_of(std::span(b).first(52)), 0u);
  auto index = LevelIndex::parse(b, "idx");
  ASSERT_FALSE(index);
  EXPECT_NE(index.error().message.find("truncated or inconsistent"), std::string::npos)
      << index.error().message;
}

}  // namespace relief::tiles
