// `relief render`, headless through EGL on Mesa's llvmpipe: no cracks on steep
// terrain from many oblique viewpoints, golden images of fixed views of the
// real SRTM data with and without imagery, and bad input.
#include <gtest/gtest.h>

#include <cmath>
#include <fstream>

#include <fmt/format.h>
#include <nlohmann/json.hpp>

#include "images.h"
#include "relief/base/file_io.h"
#include "relief/tiles/codec.h"
#include "test_support.h"

namespace relief::testing {
namespace {
namespace fs = std::filesystem;

// Stores built once for all tests of this binary.
class Stores : public ::testing::Environment {
 public:
  static fs::path pyrenees() { return dir() / "pyrenees"; }
  static fs::path world() { return dir() / "world"; }
  static fs::path sar() { return dir() / "sar"; }
  static fs::path landsat() { return dir() / "landsat"; }
  void SetUp() override {
    ASSERT_EQ(run_relief({"build", data("srtm/N41E001.hgt.zip"), data("srtm/N42E001.hgt.zip"),
                          "--kind", "elevation", "-o", pyrenees().string(), "-q"})
                  .exit_code,
              0);
    ASSERT_EQ(run_relief({"build", data("imagery/world.rgb.tif"), "--kind", "imagery", "-o",
                          world().string(), "-q"})
                  .exit_code,
              0);
    ASSERT_EQ(run_relief({"build", data("imagery/RGB.byte.tif"), "--kind", "imagery", "-o",
                          landsat().string(), "-q"})
                  .exit_code,
              0);
  }

 private:
  static fs::path dir() {
    static ScratchDir d("render_stores");
    return d.path();
  }
};
const auto* const kStores = ::testing::AddGlobalTestEnvironment(new Stores);

Image render(const std::vector<std::string>& extra, int w, int h, const fs::path& out) {
  std::vector<std::string> args = {"render", Stores::pyrenees().string(),
                                   "--size", std::to_string(w) + "x" + std::to_string(h),
                                   "-o",     out.string()};
  args.insert(args.end(), extra.begin(), extra.end());
  auto r = run_relief(args, kNoMesaLeakReport);
  EXPECT_EQ(r.exit_code, 0) << r.err;
  return read_png(out, w, h);
}

TEST(Render, NoCracksFromObliqueViewsOfSteepTerrain) {
  ScratchDir dir("render_cracks");
  // Views that see only ground (pitch below -fov/2): any sky pixel is a crack.
  const double views[][5] = {{1.45, 42.55, 3600, 20, -50},  {1.62, 42.62, 4200, 135, -40},
                             {1.30, 42.45, 3800, 250, -65}, {1.75, 42.50, 3500, 310, -38},
                             {1.55, 42.70, 5000, 90, -55},  {1.20, 42.60, 4000, 180, -45}};
  int n = 0;
  for (const auto& v : views) {
    SCOPED_TRACE(n);
    const std::string camera = fmt::format("{},{},{},{},{},0", v[0], v[1], v[2], v[3], v[4]);
    const fs::path out = dir / ("crack" + std::to_string(n++) + ".png");
    const Image img =
        render({"--camera", camera, "--sky", "255,0,255", "--pixel-error", "1.5"}, 240, 180, out);
    EXPECT_EQ(count_colour(img, 255, 0, 255), 0u) << out;
  }
}

// Compares with tests/render/golden/NAME.png; on failure writes the frame and
// a difference image next to it in the scratch directory.
void expect_golden(const std::string& name, const std::vector<std::string>& args, int w, int h) {
  ScratchDir dir("render_golden_" + name);
  const Image got = render(args, w, h, dir / (name + ".png"));
  const fs::path golden = fs::path(RELIEF_SOURCE_DIR) / "tests/render/golden" / (name + ".png");
  if (std::getenv("RELIEF_UPDATE_GOLDEN")) {
    fs::copy_file(dir / (name + ".png"), golden, fs::copy_options::overwrite_existing);
    return;
  }
  const Image want = read_png(golden, w, h);
  size_t far = 0;
  double total = 0;
  tiles::Raster diff(tiles::SampleType::UInt8, 4, w, h);
  for (size_t p = 0; p < got.rgba.size(); p += 4) {
    int worst = 0;
    for (int c = 0; c < 3; ++c)
      worst = std::max(worst, std::abs(got.rgba[p + c] - want.rgba[p + c]));
    total += worst;
    far += worst > 24;
    diff.u8()[p] = diff.u8()[p + 1] = diff.u8()[p + 2] =
        static_cast<uint8_t>(std::min(255, worst * 8));
    diff.u8()[p + 3] = 255;
  }
  const double mean = total / (w * h);
  if (mean > 1.5 || far > static_cast<size_t>(w * h / 200)) {
    auto png = tiles::encode(diff, tiles::CodecOptions{tiles::Codec::Png});
    const fs::path keep = fs::temp_directory_path() / ("relief-" + name + "-diff.png");
    (void)write_file_atomic(keep, *png);
    fs::copy_file(dir / (name + ".png"), fs::temp_directory_path() / ("relief-" + name + ".png"),
                  fs::copy_options::overwrite_existing);
    ADD_FAILURE() << name << ": mean difference " << mean << ", " << far
                  << " pixels differ by more than 24; see " << keep;
  }
}

TEST(Render, GoldenImages) {
  expect_golden("pyrenees_oblique", {"--look-at", "1.5,42.5,1500,40000,0,-30"}, 160, 120);
  expect_golden("pyrenees_imagery",
                {"--look-at", "1.4,42.6,1500,25000,60,-40", "--imagery", Stores::world().string()},
                160, 120);
  expect_golden("globe_imagery",
                {"--camera", "1.5,20,8000000,0,-90,0", "--imagery", Stores::world().string()}, 160,
                120);
}

// Imagery finer than the terrain needs: over flat ground (the Bahamas, no
// elevation data) the geometric error alone would keep quads at level 3 and
// drape 20 km texels; quads split until a texel covers at most a pixel
// (seed 003 §1.4.2 step 5). Where the imagery has no data the terrain shows
// its own colours, not black.
TEST(Render, DrapedImageryIsDrawnAtTheResolutionOfThePixels) {
  ScratchDir dir("render_landsat");
  const fs::path stats = dir / "s.json";
  const Image img = render({"--camera", "-77.8,24.6,400000,0,-90,0", "--imagery",
                            Stores::landsat().string(), "--stats", stats.string()},
                           320, 240, dir / "f.png");
  std::ifstream in(stats);
  const auto j = nlohmann::json::parse(in);
  // 320 x 240 at 60 degrees: 1 px is 1.9 km at 400 km; level-6 texels are
  // 1.2 km, level-5 ones 2.4 km.
  int deepest = 0;
  for (const auto& [level, n] : j["quads_per_level"].items())
    deepest = std::max(deepest, std::stoi(level));
  EXPECT_GE(deepest, 6);
  EXPECT_EQ(count_colour(img, 0, 0, 0), 0u);
}

TEST(Render, StatisticsDescribeTheFrame) {
  ScratchDir dir("render_stats");
  const fs::path stats = dir / "s.json";
  render({"--look-at", "1.5,42.5,1500,40000,0,-30", "--stats", stats.string()}, 200, 150,
         dir / "f.png");
  std::ifstream in(stats);
  const auto j = nlohmann::json::parse(in);
  EXPECT_GT(j["quads"].get<int>(), 10);
  // Every quad in one multi-draw; its tiles uploaded once (a still: one frame).
  EXPECT_EQ(j["draw_calls"], 1);
  EXPECT_GT(j["triangles"].get<int64_t>(), 0);
  EXPECT_DOUBLE_EQ(j["triangles_per_pixel"].get<double>(),
                   j["triangles"].get<double>() / (200.0 * 150.0));
  EXPECT_GT(j["uploaded_bytes"]["geometry"].get<int64_t>(), 0);
  EXPECT_EQ(j["uploaded_bytes"]["textures"], j["gpu"]["bytes"]);
  EXPECT_GE(j["gpu"]["slots"].get<int>(), j["gpu"]["textures"].get<int>());
  EXPECT_LE(j["max_error_pixels"].get<double>(), 1.0);
  int sum = 0;
  for (const auto& [level, n] : j["quads_per_level"].items()) sum += n.get<int>();
  EXPECT_EQ(sum, j["quads"].get<int>());
}

// A path that holds one view, complete frames: the first uploads the tiles
// and the geometry, the next ones nothing; every frame is one draw call.
TEST(Render, AStaticViewUploadsNothingAfterItsFirstCompleteFrame) {
  ScratchDir dir("render_static_path");
  const fs::path path = dir / "p.json", stats = dir / "s.json";
  const std::string camera = "[1.45, 42.55, 3600, 20, -50, 0]";
  std::ofstream(path) << "{\"fps\": 10, \"keyframes\": [{\"time\": 0, \"camera\": " << camera
                      << "}, {\"time\": 0.3, \"camera\": " << camera << "}]}";
  auto r = run_relief({"render", Stores::pyrenees().string(), "--path", path.string(), "-o",
                       (dir / "frames").string(), "--size", "120x90", "--mode", "complete",
                       "--stats", stats.string(), "--no-frames"},
                      kNoMesaLeakReport);
  ASSERT_EQ(r.exit_code, 0) << r.err;
  std::ifstream in(stats);
  const auto frames = nlohmann::json::parse(in)["frames"];
  ASSERT_GE(frames.size(), 3u);
  EXPECT_GT(frames[0]["uploaded_bytes"]["geometry"].get<int64_t>(), 0);
  EXPECT_GT(frames[0]["uploaded_bytes"]["textures"].get<int64_t>(), 0);
  for (size_t i = 0; i < frames.size(); ++i) {
    EXPECT_EQ(frames[i]["draw_calls"], 1) << i;
    if (i == 0) continue;
    EXPECT_EQ(frames[i]["uploaded_bytes"]["geometry"], 0) << i;
    EXPECT_EQ(frames[i]["uploaded_bytes"]["textures"], 0) << i;
  }
}

TEST(Render, BadInputIsAOneLineError) {
  ScratchDir dir("render_bad");
  const std::string out = (dir / "f.png").string(), store = Stores::pyrenees().string();
  ASSERT_EQ(run_relief({"build", data("sar/umbra_mount_yasur.tif"), "--kind", "sar", "-o",
                        (dir / "sar").string(), "-q"})
                .exit_code,
            0);
  auto expect_error = [&](std::vector<std::string> args, const std::string& needle) {
    auto r = run_relief(args);
    EXPECT_TRUE(is_one_line_error(r, needle)) << needle << ": " << r.err;
    EXPECT_FALSE(fs::exists(out));
  };
  const std::string cam = "1.5,42.5,5000,0,-30,0";
  expect_error({"render", store, "--camera", "1.5,42.5,-5000,0,-30,0", "-o", out},
               "inside the ellipsoid");
  expect_error({"render", store, "--camera", "1.5,42.5,300,0,-30,0", "-o", out},
               "below the ground");
  expect_error({"render", (dir / "missing").string(), "--camera", cam, "-o", out}, "missing");
  expect_error({"render", (dir / "sar").string(), "--camera", cam, "-o", out}, "holds sar data");
  expect_error({"render", store, "--imagery", store, "--camera", cam, "-o", out},
               "--imagery must be an imagery store");
  expect_error({"render", store, "--camera", cam, "--size", "0x0", "-o", out}, "--size");
  expect_error({"render", store, "--camera", cam, "--size", "100000x10", "-o", out}, "--size");
  expect_error({"render", store, "--camera", "1,2,3", "-o", out}, "6 comma-separated");
  expect_error({"render", store, "-o", out}, "--camera");
  expect_error({"render", store, "--camera", cam, "--pixel-error", "0", "-o", out},
               "--pixel-error");
}

}  // namespace
}  // namespace relief::testing
