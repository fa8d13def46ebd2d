// relief's terrain read by decoders relief did not write: CesiumJS's own
// CesiumTerrainProvider and sampleTerrain, and loaders.gl's
// QuantizedMeshLoader, under node (tests/web/js/decode_terrain.cjs, its
// packages pinned by package-lock.json and installed by scripts/setup.sh --web).
#include <gtest/gtest.h>

#include <signal.h>
#include <sys/wait.h>

#include <nlohmann/json.hpp>

#include "qm_decoder.h"
#include "relief/base/file_io.h"
#include "relief/tiles/store.h"
#include "relief/web/quantized_mesh.h"
#include "relief/web/terrain_tiler.h"
#include "servers.h"
#include "test_support.h"
#include "web_js.h"

namespace relief::web {
namespace {

namespace fs = std::filesystem;

class IndependentDecoders : public testing::SmallStoreSuite {
 protected:
  void SetUp() override {
    ASSERT_TRUE(fs::exists(fs::path(RELIEF_WEB_JS_DIR) / "node_modules/cesium"))
        << "CesiumJS is missing: run scripts/setup.sh --web (npm ci in tests/web/js)";
  }

  // Exports the store with `extra` options (with `served`, also starts
  // `relief serve` and reads from it), then asks CesiumJS and loaders.gl
  // for heights at lattice points of the finest level and for a few tiles.
  void check(const std::vector<std::string>& extra, double max_error, bool served = false) {
    testing::ScratchDir dir("web_decoders");
    const fs::path out = dir / "terrain";
    std::vector<std::string> args = {"export", store().string(), "--format", "quantized-mesh",
                                     "-o",     out.string(),     "-q"};
    args.insert(args.end(), extra.begin(), extra.end());
    auto r = testing::run_relief(args);
    ASSERT_EQ(r.exit_code, 0) << r.err;
    std::string source = out.string();
    int server = 0;
    if (served) {
      const int port = testing::free_port();
      server = testing::spawn_relief({"serve", store().string(), "--port", std::to_string(port)});
      testing::wait_for(port);
      source = "http://127.0.0.1:" + std::to_string(port) + "/terrain/";
    }
    const struct Stop {
      int pid;
      ~Stop() {
        if (pid > 0) ::kill(pid, SIGTERM), ::waitpid(pid, nullptr, 0);
      }
    } stop{server};

    auto opened = tiles::Store::open(store());
    ASSERT_TRUE(opened.has_value());
    auto shared = std::make_shared<const tiles::Store>(std::move(*opened));
    const tiles::Store& s = *shared;
    auto tiler = TerrainTiler::create(shared);
    ASSERT_TRUE(tiler.has_value());
    const int level = tiler->max_level();
    const auto keys = tiler->available_tiles(level);

    // Points on lattice corners (as the 16-bit u, v place them), expected
    // heights the mean of the 4 samples around each, read from the store.
    nlohmann::json request = {{"level", level}, {"points", nlohmann::json::array()}};
    std::vector<double> expected;
    for (const auto& p : testing::random_lattice_points(s, *tiler, level, 20, 42)) {
      request["points"].push_back({p.lon, p.lat});
      expected.push_back(p.height);
    }
    std::vector<TerrainKey> tiles = {{0, 0, 0}, {0, 1, 0}, keys.front(), keys.back()};
    tiles.push_back(tiler->available_tiles(6).front());
    request["tiles"] = nlohmann::json::array();
    for (const TerrainKey& k : tiles) request["tiles"].push_back({k.level, k.x, k.y});
    ASSERT_TRUE(write_text_file_atomic(dir / "request.json", request.dump()).has_value());

    int status = -1;
    const std::string text =
        testing::run_node({(fs::path(RELIEF_WEB_JS_DIR) / "decode_terrain.cjs").string(), source,
                           (dir / "request.json").string()},
                          status);
    ASSERT_EQ(status, 0) << text;
    const auto result = nlohmann::json::parse(text);
    EXPECT_EQ(result["cesiumVersion"], "1.140.0");
    EXPECT_EQ(result["hasVertexNormals"], true);
    ASSERT_EQ(result["heights"].size(), expected.size());
    for (size_t i = 0; i < expected.size(); ++i) {
      ASSERT_TRUE(result["heights"][i].is_number()) << "point " << i << " has no height";
      // The mesh within max_error of the lattice, heights within 16-bit steps.
      EXPECT_NEAR(result["heights"][i].get<double>(), expected[i], max_error + 0.1)
          << "point " << i << " " << request["points"][i];
    }
    for (size_t t = 0; t < tiles.size(); ++t) {
      const auto& got = result["tiles"][t];
      SCOPED_TRACE(tiles[t].to_string());
      EXPECT_EQ(got["available"], true);
      auto bytes = read_file(out / (tiles[t].to_string() + ".terrain"), 1 << 24);
      ASSERT_TRUE(bytes.has_value());
      const auto mine = testing::decode_quantized_mesh(testing::gunzip(*bytes));
      const auto& cesium = got["cesium"];
      const auto& loaders = got["loaders"];
      EXPECT_EQ(cesium["vertexCount"], mine.u.size());
      EXPECT_EQ(loaders["vertexCount"], mine.u.size());
      EXPECT_EQ(cesium["triangleCount"], mine.indices.size() / 3);
      EXPECT_EQ(loaders["triangleCount"], mine.indices.size() / 3);
      EXPECT_EQ(cesium["minimumHeight"], mine.min_height);
      EXPECT_EQ(cesium["maximumHeight"], mine.max_height);
      EXPECT_EQ(cesium["westIndices"], mine.west.size());
      EXPECT_EQ(cesium["northIndices"], mine.north.size());
      EXPECT_EQ(cesium["encodedNormalsLength"], 2 * mine.u.size());
      // The header's horizon point hides the vertices where it hides
      // itself (checked by Cesium's occluder); none at level 0.
      if (tiles[t].level == 0) {
        EXPECT_TRUE(cesium["horizonOcclusionPoint"][0].is_null());
      } else {
        EXPECT_EQ(cesium["hopHeaderCoversVertices"], true);
      }
    }
  }
};

TEST_F(IndependentDecoders, CesiumAndLoadersGlReadTheSimplifiedTerrain) {
  auto opened = tiles::Store::open(store());
  ASSERT_TRUE(opened.has_value());
  check({}, cesium_level_error(opened->manifest().max_level) / 8);
}

TEST_F(IndependentDecoders, CesiumReadsTheFullLatticeExactly) {
  check({"--max-error", "0"}, 0);
}

// The server's tiles, made on request, against the exported files (the
// tile reports compare with the files) and the store's heights.
TEST_F(IndependentDecoders, CesiumReadsReliefServesTerrainRoutes) {
  auto opened = tiles::Store::open(store());
  ASSERT_TRUE(opened.has_value());
  check({}, cesium_level_error(opened->manifest().max_level) / 8, true);
}

}  // namespace
}  // namespace relief::web
