#include "relief/tiles/store_layout.h"

#include <gtest/gtest.h>

#include <random>

namespace relief::tiles {

TEST(StoreLayout, SingleBlockUpToLevelSix) {
  EXPECT_EQ(tile_relative_path({0, 0, 0}), "0/000.rtile");
  EXPECT_EQ(tile_relative_path({1, 1, 1}), "1/003.rtile");
  EXPECT_EQ(tile_relative_path({6, 63, 63}), "6/fff.rtile");
  EXPECT_EQ(tile_relative_path({7, 0, 0}), "7/000/000.rtile");
  EXPECT_EQ(tile_relative_path({7, 127, 127}), "7/003/fff.rtile");
  EXPECT_EQ(tile_relative_path({13, 0, 0}), "13/000/000/000.rtile");
  EXPECT_EQ(level_index_relative_path(4), "4/index.rli");
}

TEST(StoreLayout, PathsInvertAndNoDirectoryExceeds4096Entries) {
  std::mt19937 rng(11);
  for (int n = 0; n < 5000; ++n) {
    const int level = static_cast<int>(rng() % 31);
    const uint32_t t = geo::TileKey::tiles_per_side(level);
    const geo::TileKey k{level, static_cast<uint32_t>(rng() % t), static_cast<uint32_t>(rng() % t)};
    const std::string p = tile_relative_path(k);
    EXPECT_EQ(tile_key_from_relative_path(p), k) << p;
    size_t start = p.find('/') + 1;
    for (size_t slash; (slash = p.find('/', start)) != std::string::npos; start = slash + 1) {
      EXPECT_EQ(slash - start, 3u);  // three hex digits: at most 4096 names
    }
  }
}

TEST(StoreLayout, RejectsNonTilePaths) {
  for (const char* bad :
       {"", "manifest.json", "0/index.rli", "../0/000.rtile", "7/000.rtile", "1/004.rtile",
        "x/000.rtile", "0/00.rtile", "0/zzz.rtile", "99/000.rtile"}) {
    EXPECT_FALSE(tile_key_from_relative_path(bad).has_value()) << bad;
  }
}

}  // namespace relief::tiles
