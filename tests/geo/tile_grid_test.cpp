#include "relief/geo/tile_grid.h"

#include <gtest/gtest.h>

#include <random>

namespace relief::geo {

TEST(TileGrid, DefaultsAre512By256WithBorder9) {
  TileGrid g;
  EXPECT_EQ(g.width(), 512);
  EXPECT_EQ(g.height(), 256);
  EXPECT_EQ(g.border(), 9);
  EXPECT_EQ(g.padded_width(), 530);
  EXPECT_DOUBLE_EQ(g.sample_spacing(0), 0.703125);
  EXPECT_DOUBLE_EQ(g.sample_spacing(10), 0.703125 / 1024);
}

TEST(TileGrid, RejectsBadParameters) {
  EXPECT_FALSE(TileGrid::create(0, 1).has_value());
  EXPECT_FALSE(TileGrid::create(8, -1).has_value());
  EXPECT_FALSE(TileGrid::create(4, 17).has_value());
  EXPECT_TRUE(TileGrid::create(4, 16).has_value());
}

// Sample registration: interior sample (i, j) is the centre of a cell of size d.
TEST(TileGrid, SampleRegistrationIsCellCentred) {
  TileGrid g;
  const TileKey t{0, 0, 0};
  EXPECT_DOUBLE_EQ(g.sample_lon(t, 0), -180 + 0.703125 / 2);
  EXPECT_DOUBLE_EQ(g.sample_lat(t, 0), 90 - 0.703125 / 2);
  EXPECT_DOUBLE_EQ(g.sample_lon(t, 511), 180 - 0.703125 / 2);
  EXPECT_DOUBLE_EQ(g.sample_lat(t, 255), -90 + 0.703125 / 2);
  // Border samples continue the same lattice into the neighbours.
  EXPECT_DOUBLE_EQ(g.sample_lon(t, -1), -180 - 0.703125 / 2);
  const TileKey k{10, 512 + 3, 270};
  const double d = g.sample_spacing(10);
  EXPECT_DOUBLE_EQ(g.sample_lon(k, 512), g.sample_lon(*k.neighbour(1, 0), 0));
  EXPECT_NEAR(g.sample_lat(k, -1) - g.sample_lat(*k.neighbour(0, -1), 255), 0, 1e-12);
  EXPECT_NEAR(g.sample_lon(k, 1) - g.sample_lon(k, 0), d, 1e-12);
}

// A parent sample centre is the mean of its 2 x 2 children's centres.
TEST(TileGrid, ParentSampleIsCentreOfItsChildren) {
  TileGrid g;
  const TileKey p{6, 40, 20};
  const TileKey c = p.child(1, 0);
  const int pi = 256 + 10, pj = 7;  // lies in child (1, 0)
  const int ci = 2 * (pi - 256), cj = 2 * pj;
  EXPECT_NEAR(g.sample_lon(p, pi), (g.sample_lon(c, ci) + g.sample_lon(c, ci + 1)) / 2, 1e-12);
  EXPECT_NEAR(g.sample_lat(p, pj), (g.sample_lat(c, cj) + g.sample_lat(c, cj + 1)) / 2, 1e-12);
}

TEST(TileGrid, LocateInvertsSamplePositions) {
  TileGrid g;
  std::mt19937 rng(3);
  for (int n = 0; n < 2000; ++n) {
    const int level = static_cast<int>(rng() % 16);
    const uint32_t tiles = TileKey::tiles_per_side(level);
    const TileKey t{level, static_cast<uint32_t>(rng() % tiles),
                    static_cast<uint32_t>(rng() % tiles)};
    const int i = static_cast<int>(rng() % 512), j = static_cast<int>(rng() % 256);
    const SampleIndex s = g.locate(level, g.sample_lon(t, i), g.sample_lat(t, j));
    EXPECT_EQ(s.tile, t);
    EXPECT_EQ(s.i, i);
    EXPECT_EQ(s.j, j);
  }
  EXPECT_EQ(g.locate(3, 180.0, 0).tile.x, 0u);  // wraps to -180
  EXPECT_EQ(g.locate(3, -180.0, 90).tile.y, 0u);
  EXPECT_EQ(g.locate(3, 0, -90).tile.y, 7u);
}

TEST(TileGrid, LevelForSpacing) {
  TileGrid g;
  EXPECT_EQ(g.level_for_spacing(0.703125), 0);
  EXPECT_EQ(g.level_for_spacing(0.7), 1);
  EXPECT_EQ(g.level_for_spacing(3.0 / 3600), 10);  // SRTM3 -> 0.000687 deg samples
}

}  // namespace relief::geo
