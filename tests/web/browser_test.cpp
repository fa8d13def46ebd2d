// relief serve's /view/ page in a real browser: Debian's Chromium, headless,
// WebGL on SwiftShader, driven by tests/web/js/browser_view.cjs. The page
// must load every tile its view needs, CesiumJS must read the store's
// heights from it, its camera must be relief render's camera, and its frame
// must cover the same pixels with terrain as relief render's.
#include <gtest/gtest.h>
#include <signal.h>
#include <sys/wait.h>

#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "images.h"
#include "relief/base/file_io.h"
#include "relief/lod/camera.h"
#include "relief/tiles/store.h"
#include "relief/web/quantized_mesh.h"
#include "relief/web/raster_tiles.h"
#include "relief/web/terrain_tiler.h"
#include "servers.h"
#include "test_support.h"
#include "web_js.h"

namespace relief::web {
namespace {

namespace fs = std::filesystem;

constexpr int kWidth = 960, kHeight = 540;
constexpr uint8_t kSky[3] = {255, 0, 255};
// Over N42E001 near the foot of the Pyrenees, looking north across them
// with sky above the crest.
constexpr const char* kCamera = "1.5,42.2,2500,0,-10,0";
constexpr double kFov = 60;
// Cameras whose Cesium basis is compared with lod::make_view's: turned,
// pitched and rolled both ways, with another field of view.
constexpr const char* kCameras[] = {"1.5,42.2,2500,0,-10,0", "1.5,42.2,2500,30,-20,15",
                                    "2.1,42.9,8000,-120,-45,-30", "1.2,42.4,4000,200,5,170"};
constexpr double kCamerasFov = 45;

lod::Camera camera_of(const std::string& text, double fov) {
  double v[6];
  EXPECT_EQ(std::sscanf(text.c_str(), "%lf,%lf,%lf,%lf,%lf,%lf", &v[0], &v[1], &v[2], &v[3], &v[4],
                        &v[5]),
            6);
  return lod::Camera{v[0], v[1], v[2], v[3], v[4], v[5], fov, kWidth, kHeight};
}

void expect_vector(const nlohmann::json& got, const lod::Vec3& want, double tolerance,
                   const char* what) {
  ASSERT_EQ(got.size(), 3u) << what;
  EXPECT_NEAR(got[0].get<double>(), want.x, tolerance) << what;
  EXPECT_NEAR(got[1].get<double>(), want.y, tolerance) << what;
  EXPECT_NEAR(got[2].get<double>(), want.z, tolerance) << what;
}

// `relief serve STORE` with the repository's web root, for one test.
struct ServedStore {
  int port = testing::free_port(), pid = 0;
  explicit ServedStore(const fs::path& store, std::vector<std::string> more = {}) {
    std::vector<std::string> args = {"serve",      store.string(), "--port", std::to_string(port),
                                     "--web-root", RELIEF_WEB_ROOT};
    args.insert(args.end(), more.begin(), more.end());
    pid = testing::spawn_relief(args);
    testing::wait_for(port);
  }
  ~ServedStore() { ::kill(pid, SIGTERM), ::waitpid(pid, nullptr, 0); }
  ServedStore(const ServedStore&) = delete;
  ServedStore& operator=(const ServedStore&) = delete;
};

class BrowserView : public testing::SmallStoreSuite {
 protected:
  void SetUp() override {
    const std::pair<fs::path, const char*> needed[] = {
        {"/usr/bin/chromium", "Debian's chromium"},
        {fs::path(RELIEF_WEB_JS_DIR) / "node_modules/puppeteer-core", "puppeteer-core"},
        {fs::path(RELIEF_WEB_ROOT) / "node_modules/cesium/Build/Cesium/Cesium.js", "CesiumJS"}};
    for (const auto& [path, what] : needed) {
      ASSERT_TRUE(fs::exists(path))
          << what << " (" << path << ") is missing: run scripts/setup.sh --web";
    }
  }
};

TEST_F(BrowserView, CesiumShowsTheServedTerrainAsReliefRenderDoes) {
  testing::ScratchDir dir("browser_view");
  auto opened = tiles::Store::open(store());
  ASSERT_TRUE(opened.has_value());
  auto shared = std::make_shared<const tiles::Store>(std::move(*opened));
  auto tiler = TerrainTiler::create(shared);
  ASSERT_TRUE(tiler.has_value());
  const int level = tiler->max_level();
  const auto points = testing::random_lattice_points(*shared, *tiler, level, 20, 43);

  const std::string size = std::to_string(kWidth) + "x" + std::to_string(kHeight);
  const std::string sky = "255,0,255";
  const auto rendered = testing::run_relief(
      {"render", store().string(), "--camera", kCamera, "--fov", std::to_string(kFov), "--size",
       size, "--sky", sky, "-o", (dir / "relief.png").string()},
      testing::kNoMesaLeakReport);
  ASSERT_EQ(rendered.exit_code, 0) << rendered.err;

  const ServedStore served(store());
  const int port = served.port;

  nlohmann::json request = {{"url", "http://127.0.0.1:" + std::to_string(port) + "/view/#camera=" +
                                        kCamera + "&fov=" + std::to_string(kFov) + "&sky=" + sky},
                            {"width", kWidth},
                            {"height", kHeight},
                            {"screenshot", (dir / "cesium.png").string()},
                            {"timeoutMs", 120000},
                            {"points", nlohmann::json::array()},
                            {"cameras", kCameras},
                            {"fov", kCamerasFov}};
  for (const auto& p : points) request["points"].push_back({p.lon, p.lat});
  ASSERT_TRUE(write_text_file_atomic(dir / "request.json", request.dump()).has_value());
  int status = -1;
  const std::string text =
      testing::run_node({(fs::path(RELIEF_WEB_JS_DIR) / "browser_view.cjs").string(),
                         (dir / "request.json").string()},
                        status);
  ASSERT_EQ(status, 0) << text;
  const auto result = nlohmann::json::parse(text);
  std::cout << "browser_view: " << result["requests"] << " terrain requests, " << result["bytes"]
            << " bytes; timings (ms) " << result["timings"] << "\n";

  EXPECT_EQ(result["ready"], true);
  EXPECT_GT(result["requests"].get<int>(), 2);  // layer.json, the roots, ...
  EXPECT_GT(result["bytes"].get<int>(), 0);

  // Heights: the finest level's mesh is within an eighth of the level's error.
  const double tolerance = cesium_level_error(level) / 8 + 0.1;
  ASSERT_EQ(result["heights"].size(), points.size());
  for (size_t i = 0; i < points.size(); ++i) {
    ASSERT_TRUE(result["heights"][i].is_number()) << "point " << i << " has no height";
    EXPECT_NEAR(result["heights"][i].get<double>(), points[i].height, tolerance)
        << "point " << i << " " << points[i].lon << "," << points[i].lat;
  }

  // The camera: Cesium's basis and vertical field of view are relief's.
  ASSERT_EQ(result["cameras"].size(), std::size(kCameras));
  for (size_t i = 0; i < std::size(kCameras); ++i) {
    SCOPED_TRACE(kCameras[i]);
    auto view = lod::make_view(camera_of(kCameras[i], kCamerasFov));
    ASSERT_TRUE(view.has_value());
    const auto& got = result["cameras"][i];
    expect_vector(got["position"], view->eye, 0.01, "eye");
    expect_vector(got["direction"], view->forward, 1e-5, "forward");
    expect_vector(got["up"], view->up, 1e-5, "up");
    expect_vector(got["right"], view->right, 1e-5, "right");
    EXPECT_NEAR(got["fovy"].get<double>(), kCamerasFov * M_PI / 180, 1e-9);
  }

  // Terrain against sky, pixel by pixel: intersection over union of the
  // terrain pixels (everything not exactly the sky colour).
  const auto mine = testing::read_png(dir / "relief.png", kWidth, kHeight);
  const auto theirs = testing::read_png(dir / "cesium.png", kWidth, kHeight);
  auto terrain = [](const testing::Image& im, size_t p) {
    return !(im.rgba[p] == kSky[0] && im.rgba[p + 1] == kSky[1] && im.rgba[p + 2] == kSky[2]);
  };
  size_t both = 0, either = 0, only_mine = 0, only_theirs = 0;
  for (size_t p = 0; p < mine.rgba.size(); p += 4) {
    const bool a = terrain(mine, p), b = terrain(theirs, p);
    both += a && b;
    either += a || b;
    only_mine += a && !b;
    only_theirs += b && !a;
  }
  ASSERT_GT(either, 0u);
  const double iou = static_cast<double>(both) / static_cast<double>(either);
  std::cout << "browser_view: terrain IoU " << iou << " (" << both << " pixels in both, "
            << only_mine << " only relief's, " << only_theirs << " only Cesium's)\n";
  const size_t pixels = static_cast<size_t>(kWidth) * kHeight;
  EXPECT_LT(either, pixels) << "no sky in the view";
  if (iou < 0.95) {
    const fs::path keep = fs::temp_directory_path() / "relief_browser_view";
    fs::create_directories(keep);
    fs::copy_file(dir / "relief.png", keep / "relief.png", fs::copy_options::overwrite_existing);
    fs::copy_file(dir / "cesium.png", keep / "cesium.png", fs::copy_options::overwrite_existing);
    ADD_FAILURE() << "terrain IoU " << iou << " < 0.95; frames kept in " << keep;
  }
}

// The page's imagery switch drapes `--imagery` in Cesium's geographic tiling:
// Cesium asks /imagery-geo/ for tiles (never the Web Mercator ones), every
// answer is 200, and the terrain's colours change where it is draped.
TEST_F(BrowserView, TheViewDrapesTheServedImageryInCesiumsGeographicTiling) {
  testing::ScratchDir dir("browser_imagery");
  const fs::path imagery = dir / "world";
  ASSERT_EQ(testing::run_relief({"build", testing::data("imagery/world.rgb.tif"), "--kind",
                                 "imagery", "-o", imagery.string(), "-q"})
                .exit_code,
            0);
  const ServedStore served(store(), {"--imagery", imagery.string()});
  const nlohmann::json request = {
      {"url", "http://127.0.0.1:" + std::to_string(served.port) + "/view/#camera=" + kCamera +
                  "&fov=" + std::to_string(kFov)},
      {"width", kWidth},
      {"height", kHeight},
      {"timeoutMs", 120000}};
  ASSERT_TRUE(write_text_file_atomic(dir / "request.json", request.dump()).has_value());
  int status = -1;
  const std::string text =
      testing::run_node({(fs::path(RELIEF_WEB_JS_DIR) / "browser_imagery.cjs").string(),
                         (dir / "request.json").string()},
                        status);
  ASSERT_EQ(status, 0) << text;
  const auto result = nlohmann::json::parse(text);
  int geographic = 0;
  for (const auto& r : result["responses"]) {
    const std::string path = r["path"];
    EXPECT_EQ(r["status"], 200) << path;
    if (path.starts_with("/imagery-geo/") && path.ends_with(".png")) ++geographic;
    EXPECT_FALSE(path.starts_with("/imagery/") && path.ends_with(".png")) << path;
  }
  EXPECT_GT(geographic, 0) << text;
  EXPECT_GT(result["changed"].get<double>(), 0.2) << text;
}

}  // namespace
}  // namespace relief::web

namespace relief::web {
namespace {

// The height of the Terrain-RGB tiles at a point, as MapLibre's DEM sampling
// reads them: bilinear over the 4 pixels around it at zoom z, with pixel
// (i, j)'s value at position (i, j) of the tile (MapLibre's DEMData puts it
// at the pixel's corner, half a pixel from the centre relief computed it
// for). Tolerance: the Terrain-RGB step, 0.1 m, and float arithmetic.
struct DemExpectation {
  double height = 0, tolerance = 0;
};
DemExpectation dem_height(const RasterTiler& tiler, int z, double lon, double lat) {
  const int n = tiler.tile_size();
  const double world = std::ldexp(1.0, z) * n;
  const double gx = (lon + 180) / 360 * world;
  const double gy = (1 - std::asinh(std::tan(lat * M_PI / 180)) / M_PI) / 2 * world;
  const auto at = [&](int64_t px, int64_t py) {
    const XyzKey key{z, static_cast<uint32_t>(px / n), static_cast<uint32_t>(py / n)};
    auto heights = tiler.heights(key);
    EXPECT_TRUE(heights.has_value()) << key.to_string();
    return heights ? (*heights)[static_cast<size_t>(py % n) * n + static_cast<size_t>(px % n)]
                   : 0.0;
  };
  const int64_t x0 = static_cast<int64_t>(std::floor(gx)),
                y0 = static_cast<int64_t>(std::floor(gy));
  const double fx = gx - x0, fy = gy - y0;
  const double h00 = at(x0, y0), h10 = at(x0 + 1, y0), h01 = at(x0, y0 + 1),
               h11 = at(x0 + 1, y0 + 1);
  const double top = h00 + (h10 - h00) * fx, bottom = h01 + (h11 - h01) * fx;
  return {top + (bottom - top) * fy, 0.11};
}

class BrowserMap : public BrowserView {};

TEST_F(BrowserMap, MapLibreReadsTheServedTerrainRgbHeights) {
  testing::ScratchDir dir("browser_map");
  auto opened = tiles::Store::open(store());
  ASSERT_TRUE(opened.has_value());
  auto raster = RasterTiler::create(std::make_shared<const tiles::Store>(std::move(*opened)));
  ASSERT_TRUE(raster.has_value());

  const ServedStore served(store());
  const int port = served.port;

  // Low over the Pyrenees, looking down steeply: the ground near the
  // centre is drawn from the finest DEM zoom.
  const nlohmann::json request = {
      {"url", "http://127.0.0.1:" + std::to_string(port) + "/map/#camera=1.5,42.45,9000,0,-70,0"},
      {"width", kWidth},
      {"height", kHeight},
      {"timeoutMs", 120000},
      {"count", 20},
      {"radius", 0.01}};
  ASSERT_TRUE(write_text_file_atomic(dir / "request.json", request.dump()).has_value());
  int status = -1;
  const std::string text = testing::run_node(
      {(fs::path(RELIEF_WEB_JS_DIR) / "browser_map.cjs").string(), (dir / "request.json").string()},
      status);
  ASSERT_EQ(status, 0) << text;
  const auto result = nlohmann::json::parse(text);
  std::cout << "browser_map: zoom " << result["zoom"] << ", " << result["requests"]
            << " tile requests, " << result["bytes"] << " bytes; timings (ms) " << result["timings"]
            << "\n";
  EXPECT_EQ(result["ready"], true);
  EXPECT_EQ(result["terrain"], true);
  EXPECT_GT(result["requests"].get<int>(), 0);
  ASSERT_EQ(result["heights"].size(), 20u);
  for (size_t i = 0; i < 20; ++i) {
    const auto& p = result["points"][i];
    ASSERT_TRUE(result["heights"][i].is_number()) << "point " << i << " has no height";
    const auto want =
        dem_height(*raster, raster->max_zoom(), p[0].get<double>(), p[1].get<double>());
    EXPECT_NEAR(result["heights"][i].get<double>(), want.height, want.tolerance)
        << "point " << i << " " << p;
  }
}

}  // namespace
}  // namespace relief::web
