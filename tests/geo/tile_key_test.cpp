#include "relief/geo/tile_key.h"

#include <gtest/gtest.h>

#include <random>

namespace relief::geo {

TEST(TileKey, LevelZeroCoversTheGlobe) {
  const GeoBox b = TileKey{0, 0, 0}.bounds();
  EXPECT_EQ(b.west, -180);
  EXPECT_EQ(b.east, 180);
  EXPECT_EQ(b.south, -90);
  EXPECT_EQ(b.north, 90);
}

TEST(TileKey, QuadsAreTwiceAsWideAsHigh) {
  for (int level = 0; level < 20; ++level) {
    const GeoBox b = TileKey{level, 0, 0}.bounds();
    EXPECT_DOUBLE_EQ(b.width(), 2 * b.height());
  }
}

TEST(TileKey, YGrowsSouthXGrowsEast) {
  const GeoBox b = TileKey{1, 1, 1}.bounds();
  EXPECT_EQ(b.west, 0);
  EXPECT_EQ(b.east, 180);
  EXPECT_EQ(b.north, 0);
  EXPECT_EQ(b.south, -90);
}

TEST(TileKey, ParentAndChildren) {
  const TileKey k{5, 17, 9};
  for (int cy = 0; cy < 2; ++cy) {
    for (int cx = 0; cx < 2; ++cx) {
      const TileKey c = k.child(cx, cy);
      EXPECT_EQ(c.parent(), k);
      const GeoBox cb = c.bounds(), pb = k.bounds();
      EXPECT_GE(cb.west, pb.west);
      EXPECT_LE(cb.east, pb.east);
      EXPECT_GE(cb.south, pb.south);
      EXPECT_LE(cb.north, pb.north);
    }
  }
  EXPECT_FALSE(TileKey{}.parent().has_value());
}

TEST(TileKey, NeighboursWrapAcrossTheAntimeridian) {
  const TileKey west_edge{3, 0, 2};
  EXPECT_EQ(west_edge.neighbour(-1, 0), (TileKey{3, 7, 2}));
  EXPECT_EQ((TileKey{3, 7, 2}).neighbour(1, 0), west_edge);
  EXPECT_EQ((TileKey{3, 7, 2}).neighbour(1, 1), (TileKey{3, 0, 3}));
  EXPECT_FALSE((TileKey{3, 4, 0}).neighbour(0, -1).has_value());
  EXPECT_FALSE((TileKey{3, 4, 7}).neighbour(0, 1).has_value());
  EXPECT_EQ((TileKey{0, 0, 0}).neighbour(1, 0), (TileKey{0, 0, 0}));
  // More than once around, either way.
  EXPECT_EQ((TileKey{3, 1, 2}).neighbour(-9, 0), (TileKey{3, 0, 2}));
  EXPECT_EQ((TileKey{3, 1, 2}).neighbour(17, -2), (TileKey{3, 2, 0}));
  EXPECT_EQ((TileKey{30, 5, 9}).neighbour(-6, 0), (TileKey{30, (1u << 30) - 1, 9}));
}

TEST(TileKey, MortonRoundTripAndOrder) {
  std::mt19937 rng(7);
  for (int i = 0; i < 1000; ++i) {
    const int level = static_cast<int>(rng() % 31);
    const uint32_t n = TileKey::tiles_per_side(level);
    const TileKey k{level, static_cast<uint32_t>(rng() % n), static_cast<uint32_t>(rng() % n)};
    EXPECT_EQ(TileKey::from_morton(level, k.morton()), k);
  }
  // Z order: the four children of a quad are consecutive, x varies fastest.
  EXPECT_EQ((TileKey{1, 0, 0}).morton(), 0u);
  EXPECT_EQ((TileKey{1, 1, 0}).morton(), 1u);
  EXPECT_EQ((TileKey{1, 0, 1}).morton(), 2u);
  EXPECT_EQ((TileKey{1, 1, 1}).morton(), 3u);
  EXPECT_EQ((TileKey{2, 3, 1}).morton(), 0b0111u);
}

TEST(TileKey, Quadkey) {
  EXPECT_EQ((TileKey{0, 0, 0}).quadkey(), "");
  EXPECT_EQ((TileKey{2, 3, 1}).quadkey(), "13");
  EXPECT_EQ((TileKey{3, 5, 2}).quadkey(), "121");
}

}  // namespace relief::geo
