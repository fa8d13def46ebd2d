// `relief export --format terrain-rgb|terrarium|xyz`: every available tile
// and tiles.json written, an earlier export replaced, bad arguments refused
// with one line before anything is written.
#include <gtest/gtest.h>

#include <nlohmann/json.hpp>

#include "relief/base/file_io.h"
#include "relief/tiles/store.h"
#include "relief/web/raster_tiles.h"
#include "test_support.h"

namespace relief::web {
namespace {

namespace fs = std::filesystem;

class RasterExport : public testing::SmallStoreSuite {
 protected:
  static RasterTiler tiler(int tile_size, int max_zoom = -1) {
    auto opened = tiles::Store::open(store());
    EXPECT_TRUE(opened.has_value());
    RasterTileOptions o;
    o.tile_size = tile_size, o.max_zoom = max_zoom;
    auto t = RasterTiler::create(std::make_shared<const tiles::Store>(std::move(*opened)), o);
    EXPECT_TRUE(t.has_value());
    return std::move(*t);
  }
  static testing::RunResult run(std::vector<std::string> extra) {
    std::vector<std::string> args = {"export", store().string()};
    args.insert(args.end(), extra.begin(), extra.end());
    return testing::run_relief(args);
  }
};

// The tiles the export wrote are exactly the available ones, byte for byte.
void expect_tiles(const fs::path& out, const RasterTiler& t, DemEncoding e) {
  size_t files = 0;
  for (int z = 0; z <= t.max_zoom(); ++z) {
    for (const XyzKey& k : t.available_tiles(z)) {
      auto bytes = read_file(out / (k.to_string() + ".png"), 1 << 24);
      ASSERT_TRUE(bytes.has_value()) << k.to_string();
      if (z == t.max_zoom() && files % 7 == 0) {
        auto made = t.dem_png_tile(k, e);
        ASSERT_TRUE(made.has_value());
        EXPECT_EQ(*bytes, *made) << k.to_string();
      }
      ++files;
    }
  }
  EXPECT_EQ(files + 1, testing::regular_files_under(out)) << "tiles and tiles.json, nothing else";
}

TEST_F(RasterExport, WritesEveryAvailableTileAndTileJsonAndReplacesAnEarlierExport) {
  testing::ScratchDir dir("raster_export");
  const fs::path out = dir / "dem";
  auto r = run({"--format", "terrain-rgb", "-o", out.string(), "--threads", "2", "-q"});
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_NE(r.out.find("terrain-rgb tiles, zooms 0-11"), std::string::npos) << r.out;
  expect_tiles(out, tiler(256), DemEncoding::TerrainRgb);
  auto text = read_text_file(out / "tiles.json", 1 << 20);
  ASSERT_TRUE(text.has_value());
  const auto j = nlohmann::json::parse(*text);
  EXPECT_EQ(j["tilejson"], "2.2.0");
  EXPECT_EQ(j["tiles"], nlohmann::json::array({"{z}/{x}/{y}.png"}));
  EXPECT_EQ(j["encoding"], "mapbox");
  EXPECT_EQ(j["tileSize"], 256);
  EXPECT_EQ(j["minzoom"], 0);
  EXPECT_EQ(j["maxzoom"], 11);
  EXPECT_EQ(j["bounds"].size(), 4u);
  EXPECT_TRUE(testing::temporary_files(dir.path()).empty());

  // A second export (another format, size and zoom) replaces the first.
  r = run(
      {"--format", "terrarium", "--tile-size", "512", "--max-zoom", "4", "-o", out.string(), "-q"});
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_FALSE(fs::exists(out / "11"));
  expect_tiles(out, tiler(512, 4), DemEncoding::Terrarium);
  text = read_text_file(out / "tiles.json", 1 << 20);
  ASSERT_TRUE(text.has_value());
  EXPECT_EQ(nlohmann::json::parse(*text)["encoding"], "terrarium");
  EXPECT_EQ(nlohmann::json::parse(*text)["tileSize"], 512);
  EXPECT_TRUE(testing::temporary_files(dir.path()).empty());
}

TEST_F(RasterExport, RefusesBadArgumentsWithOneLineAndWritesNothing) {
  testing::ScratchDir dir("raster_export_bad");
  const std::string out = (dir / "t").string();
  const auto refused = [&](std::vector<std::string> args, const std::string& needle) {
    return testing::is_one_line_error(run(std::move(args)), needle);
  };
  EXPECT_TRUE(refused({"--format", "xyz", "-o", out}, "--format xyz"));
  EXPECT_TRUE(refused({"--format", "terrain-rgbx", "-o", out}, "terrarium"));
  EXPECT_TRUE(refused({"--format", "terrain-rgb", "--tile-size", "300", "-o", out}, "--tile-size"));
  EXPECT_TRUE(refused({"--format", "terrarium", "--tile-size", "", "-o", out}, "--tile-size"));
  EXPECT_TRUE(refused({"--format", "terrain-rgb", "--max-zoom", "31", "-o", out}, "--max-zoom"));
  EXPECT_TRUE(refused({"--format", "terrain-rgb", "--max-zoom", "-1", "-o", out}, "--max-zoom"));
  EXPECT_TRUE(refused({"--format", "terrain-rgb", "--bbox", "3,1,2", "-o", out}, "--bbox"));
  EXPECT_TRUE(refused({"--format", "terrain-rgb", "--bbox", "5,5,6,6", "-o", out}, "--bbox"));
  EXPECT_TRUE(refused({"--format", "terrain-rgb", "--max-level", "3", "-o", out}, "--max-level"));
  EXPECT_TRUE(refused({"--format", "terrarium", "--max-error", "1", "-o", out}, "--max-error"));
  EXPECT_TRUE(
      refused({"--format", "quantized-mesh", "--tile-size", "512", "-o", out}, "--tile-size"));
  EXPECT_TRUE(refused({"--level", "3", "--max-zoom", "3", "-o", out + ".tif"}, "--max-zoom"));
  EXPECT_TRUE(refused({"--format", "terrain-rgb", "--threads", "0", "-o", out}, "--threads"));
  EXPECT_TRUE(refused({"--format", "terrain-rgb"}, "-o"));
  EXPECT_TRUE(refused({"--format", "terrain-rgb", "-o", (store() / "web").string()}, "-o"));
  ASSERT_TRUE(write_text_file_atomic(dir / "file", "not an export").has_value());
  EXPECT_TRUE(refused({"--format", "terrain-rgb", "-o", (dir / "file").string()},
                      "not an earlier web tile export"));
  fs::create_directories(dir / "other");
  ASSERT_TRUE(write_text_file_atomic(dir / "other/notes.txt", "mine").has_value());
  EXPECT_TRUE(refused({"--format", "terrarium", "-o", (dir / "other").string()},
                      "not an earlier web tile export"));
  EXPECT_TRUE(fs::exists(dir / "other/notes.txt"));
  EXPECT_FALSE(fs::exists(out));
  EXPECT_FALSE(fs::exists(out + ".tif"));
  EXPECT_TRUE(testing::temporary_files(dir.path()).empty());
  EXPECT_TRUE(
      testing::is_one_line_error(testing::run_relief({"export", (dir / "nostore").string(),
                                                      "--format", "terrain-rgb", "-o", out}),
                                 "nostore"));
}

}  // namespace
}  // namespace relief::web
