// relief's Terrain-RGB and Terrarium export read by a decoder relief did not
// write: pngjs under node, heights unpacked with MapLibre's own formula and
// factors (tests/web/js/decode_dem_png.cjs), compared with heights computed
// here from the store's samples (expected_heights.h).
#include <gtest/gtest.h>

#include <nlohmann/json.hpp>
#include <random>

#include "expected_heights.h"
#include "relief/base/file_io.h"
#include "relief/tiles/store.h"
#include "relief/web/web_mercator.h"
#include "test_support.h"
#include "web_js.h"

namespace relief::web {
namespace {

namespace fs = std::filesystem;

class DemPngDecoder : public testing::SmallStoreSuite {
 protected:
  void SetUp() override {
    ASSERT_TRUE(fs::exists(fs::path(RELIEF_WEB_JS_DIR) / "node_modules/pngjs"))
        << "pngjs is missing: run scripts/setup.sh --web (npm ci in tests/web/js)";
  }

  // Exports the store in `format` at `tile_size`, then asks node for the
  // heights of random pixels with data at each zoom.
  void check(const std::string& format, int tile_size, const std::vector<int>& zooms, double step) {
    testing::ScratchDir dir("web_dem_png");
    const fs::path out = dir / "dem";
    // A box in the middle of the data keeps the export small.
    auto r = testing::run_relief({"export", store().string(), "--format", format, "--tile-size",
                                  std::to_string(tile_size), "--bbox", "1.3,42.3,1.7,42.7", "-o",
                                  out.string(), "-q"});
    ASSERT_EQ(r.exit_code, 0) << r.err;
    auto opened = tiles::Store::open(store());
    ASSERT_TRUE(opened.has_value());
    const tiles::Store& s = *opened;
    const geo::GeoBox inside{1.3, 42.3, 1.7, 42.7};

    std::mt19937 random(static_cast<unsigned>(tile_size));
    nlohmann::json request = {{"tiles", nlohmann::json::array()}};
    std::vector<double> expected;
    const std::string encoding = format == "terrain-rgb" ? "mapbox" : "terrarium";
    for (const int z : zooms) {
      const auto range = xyz_tiles_meeting(z, inside);
      ASSERT_TRUE(range);
      for (int found = 0, attempt = 0; found < 10 && attempt < 100000; ++attempt) {
        const XyzKey k{z, range->x0 + static_cast<uint32_t>(random() % (range->x1 - range->x0 + 1)),
                       range->y0 + static_cast<uint32_t>(random() % (range->y1 - range->y0 + 1))};
        const int i = static_cast<int>(random() % tile_size);
        const int j = static_cast<int>(random() % tile_size);
        const auto p = testing::pixel_centre(k.z, k.x, k.y, tile_size, i, j);
        if (p.lon < inside.west || p.lon > inside.east || p.lat < inside.south ||
            p.lat > inside.north)
          continue;
        const auto h =
            testing::bilinear_height(s, testing::level_for_pixel(s, z, tile_size, p.lat), p);
        if (!h) continue;
        ++found;
        expected.push_back(*h);
        request["tiles"].push_back({{"file", (out / (k.to_string() + ".png")).string()},
                                    {"encoding", encoding},
                                    {"pixels", {{i, j}}}});
      }
    }
    ASSERT_EQ(expected.size(), 10 * zooms.size());
    ASSERT_TRUE(write_text_file_atomic(dir / "request.json", request.dump()).has_value());

    int status = -1;
    const std::string text =
        testing::run_node({(fs::path(RELIEF_WEB_JS_DIR) / "decode_dem_png.cjs").string(),
                           (dir / "request.json").string()},
                          status);
    ASSERT_EQ(status, 0) << text;
    const auto result = nlohmann::json::parse(text);
    EXPECT_EQ(result["pngjs"], "7.0.0");
    ASSERT_EQ(result["tiles"].size(), expected.size());
    for (size_t t = 0; t < expected.size(); ++t) {
      const auto& got = result["tiles"][t];
      SCOPED_TRACE(request["tiles"][t].dump());
      EXPECT_EQ(got["width"], tile_size);
      EXPECT_EQ(got["height"], tile_size) << "MapLibre needs square DEM tiles";
      EXPECT_EQ(got["alpha"][0], 255);
      // Half a step of the encoding, and rounding of the interpolation.
      EXPECT_NEAR(got["heights"][0].get<double>(), expected[t], step / 2 + 1e-3);
    }
  }
};

TEST_F(DemPngDecoder, MapLibreReadsTerrainRgbHeights) {
  check("terrain-rgb", 256, {7, 10, 11}, 0.1);
}

TEST_F(DemPngDecoder, MapLibreReadsTerrariumHeightsOf512PixelTiles) {
  check("terrarium", 512, {6, 9, 10}, 1.0 / 256);
}

}  // namespace
}  // namespace relief::web
