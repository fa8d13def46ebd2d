#include "relief/tiles/level_index.h"

#include <gtest/gtest.h>

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

}  // namespace relief::tiles
