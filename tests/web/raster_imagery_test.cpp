// XYZ imagery tiles of an imagery store (data/imagery/RGB.byte.tif): pixels
// checked against the bilinear colour of the store's own samples, read
// tile by tile here; transparent where the store has no data. The export.
#include <gtest/gtest.h>

#include <map>
#include <nlohmann/json.hpp>
#include <random>

#include "expected_heights.h"
#include "relief/base/file_io.h"
#include "relief/tiles/codec.h"
#include "relief/tiles/store.h"
#include "relief/web/geographic_tiles.h"
#include "relief/web/raster_tiles.h"
#include "test_support.h"

namespace relief::web {
namespace {

namespace fs = std::filesystem;
using Colour = std::array<double, 4>;

class RasterImagery : public ::testing::Test {
 protected:
  static void SetUpTestSuite() {
    dir_ = new testing::ScratchDir("web_imagery");
    ASSERT_EQ(testing::run_relief({"build", testing::data("imagery/RGB.byte.tif"), "--kind",
                                   "imagery", "-o", store_path().string(), "-q"})
                  .exit_code,
              0);
  }
  static void TearDownTestSuite() {
    delete dir_;
    dir_ = nullptr;
  }
  static fs::path store_path() { return dir_->path() / "rgb"; }

  // The store's sample at (lon, lat) of a level, tiles decoded once.
  Colour sample(const tiles::Store& s, int level, double lon, double lat) {
    const geo::SampleIndex at = s.grid().locate(level, lon, lat);
    if (!s.has_tile(at.tile)) return {0, 0, 0, 0};
    auto it = decoded_.find(at.tile);
    if (it == decoded_.end()) {
      auto tile = s.read_tile(at.tile);
      EXPECT_TRUE(tile.has_value());
      it = decoded_.emplace(at.tile, std::move(tile->raster)).first;
    }
    const int b = s.grid().border(), w = it->second.width();
    const auto p = it->second.u8().subspan(
        (static_cast<size_t>(at.j + b) * static_cast<size_t>(w) + at.i + b) * 4, 4);
    return {double(p[0]), double(p[1]), double(p[2]), double(p[3])};
  }

 private:
  static inline testing::ScratchDir* dir_ = nullptr;
  std::map<geo::TileKey, tiles::Raster> decoded_;
};

TEST_F(RasterImagery, PixelsAreBilinearColoursAndTransparentOutsideTheData) {
  auto opened = tiles::Store::open(store_path());
  ASSERT_TRUE(opened.has_value());
  auto store = std::make_shared<const tiles::Store>(std::move(*opened));
  auto tiler = RasterTiler::create(store);
  ASSERT_TRUE(tiler.has_value()) << tiler.error().message;
  EXPECT_FALSE(tiler->holds_elevation());
  EXPECT_EQ(tiler->max_zoom(), 9);  // level 8 at 23.6-25.6°: 8 + 1
  EXPECT_FALSE(tiler->dem_png_tile({0, 0, 0}, DemEncoding::TerrainRgb).has_value());

  std::mt19937 random(5);
  int opaque = 0, transparent = 0;
  for (const int z : {4, 7, 9}) {
    auto keys = tiler->available_tiles(z);
    std::shuffle(keys.begin(), keys.end(), random);
    keys.resize(std::min<size_t>(keys.size(), 2));
    for (const XyzKey& k : keys) {
      SCOPED_TRACE(k.to_string());
      auto png = tiler->imagery_png_tile(k);
      ASSERT_TRUE(png.has_value());
      auto image = tiles::decode(tiles::Codec::Png, *png, tiles::SampleType::UInt8, 4, 256, 256);
      ASSERT_TRUE(image.has_value());
      for (int n = 0; n < 1000; ++n) {
        const int i = static_cast<int>(random() % 256), j = static_cast<int>(random() % 256);
        const auto c = testing::pixel_centre(k.z, k.x, k.y, 256, i, j);
        const int level = testing::level_for_pixel(*store, z, 256, c.lat);
        const double d = store->grid().sample_spacing(level);
        const double fx = (c.lon + 180) / d - 0.5, fy = (90 - c.lat) / d - 0.5;
        const double x0 = std::floor(fx), y0 = std::floor(fy), tx = fx - x0, ty = fy - y0;
        Colour expected{};
        double alpha_sum = 0;
        for (const int dc : {0, 1}) {
          for (const int dr : {0, 1}) {
            const Colour s =
                sample(*store, level, -180 + (x0 + dc + 0.5) * d, 90 - (y0 + dr + 0.5) * d);
            const double w = (dc ? tx : 1 - tx) * (dr ? ty : 1 - ty);
            for (size_t ch = 0; ch < 4; ++ch) expected[ch] += w * s[ch];
            alpha_sum += s[3];
          }
        }
        const auto got = image->u8().subspan((static_cast<size_t>(j) * 256 + i) * 4, 4);
        if (alpha_sum == 0) {
          EXPECT_EQ(got[3], 0) << i << "," << j;
          ++transparent;
        } else if (alpha_sum == 4 * 255) {
          for (size_t ch = 0; ch < 4; ++ch)
            EXPECT_NEAR(got[ch], expected[ch], 0.5 + 1e-6) << i << "," << j << " channel " << ch;
          ++opaque;
        }
      }
    }
  }
  EXPECT_GT(opaque, 200) << transparent;
  EXPECT_GT(transparent, 200) << opaque;
}

TEST_F(RasterImagery, ExportXyzAndRefuseHeightFormats) {
  testing::ScratchDir dir("web_imagery_export");
  const fs::path out = dir / "xyz";
  auto r = testing::run_relief(
      {"export", store_path().string(), "--format", "xyz", "-o", out.string(), "-q"});
  ASSERT_EQ(r.exit_code, 0) << r.err;
  auto text = read_text_file(out / "tiles.json", 1 << 20);
  ASSERT_TRUE(text.has_value());
  const auto j = nlohmann::json::parse(*text);
  EXPECT_EQ(j["maxzoom"], 9);
  EXPECT_FALSE(j.contains("encoding"));
  auto opened = tiles::Store::open(store_path());
  ASSERT_TRUE(opened.has_value());
  auto tiler = RasterTiler::create(std::make_shared<const tiles::Store>(std::move(*opened)));
  ASSERT_TRUE(tiler.has_value());
  size_t files = 0;
  for (int z = 0; z <= 9; ++z) {
    for (const XyzKey& k : tiler->available_tiles(z)) {
      auto bytes = read_file(out / (k.to_string() + ".png"), 1 << 24);
      ASSERT_TRUE(bytes.has_value()) << k.to_string();
      EXPECT_EQ(*bytes, *tiler->imagery_png_tile(k)) << k.to_string();
      ++files;
    }
  }
  EXPECT_EQ(files + 1, testing::regular_files_under(out));

  for (const char* format : {"terrain-rgb", "terrarium"}) {
    EXPECT_TRUE(
        testing::is_one_line_error(testing::run_relief({"export", store_path().string(), "--format",
                                                        format, "-o", (dir / "dem").string()}),
                                   std::string("--format ") + format));
  }
  EXPECT_FALSE(fs::exists(dir / "dem"));
}

// --format xyz-webp: the same tiles as lossy WebP, a fraction of the PNGs'
// bytes; colours within a few levels of the PNG's, transparency the same.
TEST_F(RasterImagery, ExportXyzWebpKeepsTheColoursAndTheTransparency) {
  testing::ScratchDir dir("web_imagery_webp");
  const fs::path out = dir / "webp";
  auto r = testing::run_relief({"export", store_path().string(), "--format", "xyz-webp",
                                "--max-zoom", "7", "-o", out.string(), "-q"});
  ASSERT_EQ(r.exit_code, 0) << r.err;
  auto text = read_text_file(out / "tiles.json", 1 << 20);
  ASSERT_TRUE(text.has_value());
  EXPECT_EQ(nlohmann::json::parse(*text)["tiles"][0], "{z}/{x}/{y}.webp");
  auto opened = tiles::Store::open(store_path());
  ASSERT_TRUE(opened.has_value());
  auto tiler = RasterTiler::create(std::make_shared<const tiles::Store>(std::move(*opened)));
  ASSERT_TRUE(tiler.has_value());
  const int n = tiler->tile_size();
  uint64_t webp_bytes = 0, png_bytes = 0, files = 0;
  double difference = 0, opaque = 0;
  for (int z = 0; z <= 7; ++z) {
    for (const XyzKey& k : tiler->available_tiles(z)) {
      auto webp = read_file(out / (k.to_string() + ".webp"), 1 << 24);
      ASSERT_TRUE(webp.has_value()) << k.to_string();
      auto png = tiler->imagery_png_tile(k);
      ASSERT_TRUE(png.has_value());
      webp_bytes += webp->size(), png_bytes += png->size(), ++files;
      auto a = tiles::decode(tiles::Codec::Webp, *webp, tiles::SampleType::UInt8, 4, n, n);
      auto b = tiles::decode(tiles::Codec::Png, *png, tiles::SampleType::UInt8, 4, n, n);
      ASSERT_TRUE(a.has_value() && b.has_value()) << k.to_string();
      const auto pa = a->u8(), pb = b->u8();
      for (size_t p = 0; p < pa.size(); p += 4) {
        ASSERT_EQ(pa[p + 3], pb[p + 3]) << k.to_string() << " pixel " << p / 4;  // lossless alpha
        if (pb[p + 3] != 255) continue;
        for (int c = 0; c < 3; ++c) difference += std::abs(int{pa[p + c]} - int{pb[p + c]});
        opaque += 3;
      }
    }
  }
  EXPECT_EQ(files + 1, testing::regular_files_under(out));
  ASSERT_GT(opaque, 0);
  EXPECT_LT(difference / opaque, 4.0);  // mean colour difference, levels
  EXPECT_LT(webp_bytes * 2, png_bytes);
}

// Cesium's geographic tiling: tile (z, x, y) is the west or east half of the
// store tile (z, x / 2, y), sample for sample; tiles beyond the level's
// range or without a store tile are not available; an elevation store is
// refused by name.
TEST_F(RasterImagery, GeographicTilesAreHalvesOfTheStoresTiles) {
  auto opened = tiles::Store::open(store_path());
  ASSERT_TRUE(opened.has_value());
  const auto store = std::make_shared<const tiles::Store>(std::move(*opened));
  auto geo_tiles = GeographicTiles::create(store);
  ASSERT_TRUE(geo_tiles.has_value()) << geo_tiles.error().message;
  const int b = store->grid().border(), n = GeographicTiles::kTileSize;
  int checked = 0;
  for (int z = 0; z <= geo_tiles->max_level(); ++z) {
    for (const tiles::IndexEntry& entry : store->index(z).entries()) {
      const geo::TileKey key = entry.key;
      auto tile = store->read_tile(key);
      ASSERT_TRUE(tile.has_value());
      const int w = tile->raster.width();
      for (uint32_t half = 0; half < 2; ++half) {
        const geo::TileKey cesium{z, 2 * key.x + half, key.y};
        ASSERT_TRUE(geo_tiles->available(cesium)) << cesium.to_string();
        auto png = geo_tiles->png_tile(cesium);
        ASSERT_TRUE(png.has_value());
        auto r = tiles::decode(tiles::Codec::Png, *png, tiles::SampleType::UInt8, 4, n, n);
        ASSERT_TRUE(r.has_value());
        for (int j = 0; j < n; j += 17) {
          for (int i = 0; i < n; i += 13) {
            for (int c = 0; c < 4; ++c) {
              const size_t from =
                  (static_cast<size_t>(j + b) * w + b + half * n + static_cast<size_t>(i)) * 4 + c;
              ASSERT_EQ(r->u8()[(static_cast<size_t>(j) * n + i) * 4 + c], tile->raster.u8()[from])
                  << cesium.to_string() << " " << i << "," << j;
            }
          }
        }
        ++checked;
      }
    }
  }
  EXPECT_GT(checked, 4);
  const int top = geo_tiles->max_level();
  EXPECT_FALSE(geo_tiles->available({top + 1, 0, 0}));
  EXPECT_FALSE(geo_tiles->available({0, 2, 0}));  // two columns at level 0
  EXPECT_FALSE(geo_tiles->available({0, 0, 1}));  // one row
  EXPECT_FALSE(geo_tiles->png_tile({0, 0, 1}).has_value());
  const auto json = nlohmann::json::parse(geo_tiles->description("rgb"));
  EXPECT_EQ(json["scheme"], "geographic");
  EXPECT_EQ(json["maxzoom"], top);
}

}  // namespace
}  // namespace relief::web
