// Overlap borders equal the neighbouring tiles' interior samples, across tile
// boundaries, source boundaries and the antimeridian.
#include <gtest/gtest.h>

#include <array>
#include <cmath>
#include <cstring>
#include <optional>

#include "../support/test_support.h"
#include "built_stores.h"
#include "gdal_reference.h"

namespace relief::testing {
namespace {

bool same_sample(const tiles::Raster& a, int ai, int aj, const tiles::Raster& b, int bi, int bj) {
  const size_t px = a.bands() * tiles::sample_size(a.type());
  const auto* pa = a.bytes().data() + (static_cast<size_t>(aj) * a.width() + ai) * px;
  const auto* pb = b.bytes().data() + (static_cast<size_t>(bj) * b.width() + bi) * px;
  return std::memcmp(pa, pb, px) == 0;
}

// Checks every border sample of every tile on `level` against the neighbour
// that owns it (or nodata when there is none). Returns border samples checked.
int64_t check_borders(const tiles::Store& store, int level) {
  const auto& g = store.grid();
  const int w = g.width(), h = g.height(), b = g.border();
  int64_t checked = 0;
  for (const auto& e : store.index(level).entries()) {
    const tiles::Tile tile = must_read(store, e.key);
    std::array<std::optional<tiles::Tile>, 9> around;  // neighbour (dx, dy) at (dy+1)*3 + dx+1
    for (int k = 0; k < 9; ++k) {
      auto n = e.key.neighbour(k % 3 - 1, k / 3 - 1);
      if (k != 4 && n && store.has_tile(*n)) around[k] = must_read(store, *n);
    }
    for (int j = -b; j < h + b; ++j) {
      for (int i = -b; i < w + b; ++i) {
        if (i >= 0 && i < w && j >= 0 && j < h) continue;
        const int dx = i < 0 ? -1 : (i >= w ? 1 : 0), dy = j < 0 ? -1 : (j >= h ? 1 : 0);
        const auto& n = around[(dy + 1) * 3 + dx + 1];
        if (!n) {
          if (tile.raster.valid(i + b, j + b)) {
            ADD_FAILURE() << e.key.to_string() << " border " << i << "," << j
                          << " has data but no neighbour owns it";
            return checked;
          }
          continue;
        }
        const int ni = i - dx * w + b, nj = j - dy * h + b;
        if (!same_sample(tile.raster, i + b, j + b, n->raster, ni, nj)) {
          ADD_FAILURE() << e.key.to_string() << " border sample " << i << "," << j
                        << " differs from neighbour " << dx << "," << dy;
          return checked;
        }
        ++checked;
      }
    }
  }
  return checked;
}

TEST(Seams, BordersEqualNeighbourInteriorsAtEveryLevel) {
  const auto& store = pyrenees_store();
  int64_t checked = 0;
  for (int level = 0; level <= store.manifest().max_level; ++level)
    checked += check_borders(store, level);
  EXPECT_GT(checked, 100000);
}

TEST(Seams, NorthSouthSrtmPairIsOneSeamlessDataset) {
  const auto& store = pyrenees_store();
  // No nodata gap along 42N, where the two .hgt files meet.
  const double d = store.grid().sample_spacing(10);
  for (double lon = 1.001; lon < 2.0; lon += 5 * d) {
    for (double lat : {42.0 - 1.5 * d, 42.0 - 0.5 * d, 42.0 + 0.5 * d, 42.0 + 1.5 * d}) {
      auto v = store.sample(lon, lat, 10);
      ASSERT_TRUE(v && v->has_value()) << lon << "," << lat;
    }
  }
}

TEST(Seams, WestEastSrtmPairIsOneSeamlessDataset) {
  ingest::BuildOptions o;
  o.inputs = {data("srtm/N55W004.hgt.zip"), data("srtm/N55W003.hgt.zip")};
  o.kind = tiles::DatasetKind::Elevation;
  const auto& store = built_store("scotland", o);
  const SourceGrid west = read_source("/vsizip/" + o.inputs[0] + "/N55W004.hgt");
  const SourceGrid east = read_source("/vsizip/" + o.inputs[1] + "/N55W003.hgt");
  const auto& g = store.grid();
  const double d = g.sample_spacing(10);
  int compared = 0;
  for (double lat = 55.01; lat < 55.99; lat += 7 * d) {
    for (int k = -3; k <= 3; ++k) {
      const geo::SampleIndex s = g.locate(10, -3.0 + (k + 0.5) * d, lat);
      const double x = g.sample_lon(s.tile, s.i), y = g.sample_lat(s.tile, s.j);
      double expected = 0;
      if (!bilinear(x < -3.0 ? west : east, x, y, expected) &&
          !bilinear(x < -3.0 ? east : west, x, y, expected)) {
        continue;
      }
      auto v = store.sample(x, y, 10);
      ASSERT_TRUE(v && v->has_value()) << x << "," << y;
      EXPECT_NEAR(**v, expected, 1e-3) << x << "," << y;
      ++compared;
    }
  }
  EXPECT_GT(compared, 1000);
  EXPECT_GT(check_borders(store, 10), 10000);
}

// A DEM straddling the antimeridian: real SRTM samples placed at 179.5..180.5 E.
TEST(Seams, BordersWrapAcrossTheAntimeridian) {
  ScratchDir dir("antimeridian");
  const SourceGrid srtm = read_source("/vsizip/" + data("srtm/N42E001.hgt.zip") + "/N42E001.hgt");
  std::vector<float> values(srtm.values.begin(), srtm.values.end());
  double gt[6] = {179.5 - srtm.gt[1] / 2, srtm.gt[1], 0, srtm.gt[3], 0, srtm.gt[5]};
  const std::string input = (dir / "dateline.tif").string();
  write_geotiff(input, srtm.width, srtm.height, gt, values);
  ingest::BuildOptions o;
  o.inputs = {input};
  o.kind = tiles::DatasetKind::Elevation;
  o.max_level = 8;
  const auto& store = built_store("dateline", o);
  const uint32_t last = geo::TileKey::tiles_per_side(8) - 1;
  bool east_side = false, west_side = false;
  for (const auto& e : store.index(8).entries()) {
    east_side |= e.key.x == last;
    west_side |= e.key.x == 0;
  }
  ASSERT_TRUE(east_side && west_side) << "data on both sides of 180 degrees";
  for (int level = 0; level <= 8; ++level) check_borders(store, level);
  // West of the antimeridian the store holds the samples placed east of 180.
  SourceGrid shifted = srtm;
  shifted.gt[0] = gt[0];
  const auto& g = store.grid();
  for (double lon : {-179.9, -179.7, -179.55}) {
    const geo::SampleIndex s = g.locate(8, lon, 42.5);
    const double x = g.sample_lon(s.tile, s.i), y = g.sample_lat(s.tile, s.j);
    double expected = 0;
    ASSERT_TRUE(bilinear(shifted, x + 360.0, y, expected));
    auto v = store.sample(x, y, 8);
    ASSERT_TRUE(v && v->has_value());
    // Level 8 averages ~3 source samples per store sample: compare loosely.
    EXPECT_NEAR(**v, expected, 150.0);
  }
}

TEST(Seams, GlobalImageryWrapsAcrossTheAntimeridian) {
  ingest::BuildOptions o;
  o.inputs = {data("imagery/world.rgb.tif")};
  o.kind = tiles::DatasetKind::Imagery;
  o.codec = tiles::Codec::Png;
  o.max_level = 2;
  const auto& store = built_store("world", o);
  EXPECT_EQ(store.index(2).size(), 16u);
  EXPECT_EQ(store.index(0).size(), 1u);
  for (int level = 0; level <= 2; ++level) check_borders(store, level);
}

}  // namespace
}  // namespace relief::testing

namespace relief::testing {
namespace {

// Other tile shapes and borders keep every property: 128 x 64 tiles with a
// 2-sample border, and no border at all.
TEST(Seams, NonDefaultTileSizeAndBorder) {
  for (int border : {2, 0}) {
    SCOPED_TRACE(border);
    ingest::BuildOptions o;
    o.inputs = {data("srtm/N42E001.hgt.zip")};
    o.kind = tiles::DatasetKind::Elevation;
    o.tile_log2_height = 6;
    o.border = border;
    const auto& store = built_store("small_tiles_b" + std::to_string(border), o);
    EXPECT_EQ(store.grid().width(), 128);
    EXPECT_EQ(store.grid().height(), 64);
    EXPECT_EQ(store.manifest().max_level, 12);  // 4x smaller tiles: two more levels
    for (int level = 0; level <= 12; ++level) check_borders(store, level);
    // Same samples as the default layout: the sample lattice depends only on spacing.
    const auto& reference = pyrenees_store();
    for (double lon = 1.05; lon < 2.0; lon += 0.1) {
      for (double lat = 42.05; lat < 43.0; lat += 0.1) {
        auto a = store.sample(lon, lat, 12);
        auto b = reference.sample(lon, lat, 10);
        ASSERT_TRUE(a && b);
        ASSERT_EQ(a->has_value(), b->has_value()) << lon << "," << lat;
        if (a->has_value()) {
          EXPECT_FLOAT_EQ(**a, **b) << lon << "," << lat;
        }
      }
    }
  }
}

}  // namespace
}  // namespace relief::testing
