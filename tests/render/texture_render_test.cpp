// `relief render --texture`: SAR processed on the GPU at draw time and draped
// on the ellipsoid (no elevation store) equals the store `relief process`
// made offline, drawn as it is; an imagery store as a texture layer equals
// --imagery; paths work; bad texture options are one-line errors.
#include <gtest/gtest.h>

#include <fstream>

#include <fmt/format.h>

#include "images.h"
#include "relief/tiles/store.h"
#include "test_support.h"

namespace relief::testing {
namespace {
namespace fs = std::filesystem;

// The bundled SAR image, raw and Lee-filtered offline (radius 3 on the finest
// level, scaled per level), built once.
struct SarStores {
  ScratchDir dir{"texture_render"};
  fs::path sar = dir / "sar", lee = dir / "lee";
  SarStores() {
    EXPECT_EQ(run_relief({"build", data("sar/umbra_mount_yasur.tif"), "--kind", "sar", "-o",
                          sar.string(), "-q"})
                  .exit_code,
              0);
    EXPECT_EQ(run_relief({"process", sar.string(), "-o", lee.string(), "--op", "lee", "--param",
                          "radius=3", "-q"})
                  .exit_code,
              0);
  }
};
const SarStores& stores() {
  static SarStores s;
  return s;
}

// Straight down on the middle of the image from 300 m: the finest two levels,
// away from the data's edges.
const std::string kDown = "169.4485,-19.5273,0,300,0,-89";
constexpr int kW = 320, kH = 240;

Image render(std::vector<std::string> args, const fs::path& out) {
  args.insert(args.begin(), "render");
  for (const std::string& a :
       {std::string("--size"), fmt::format("{}x{}", kW, kH), std::string("-o"), out.string()}) {
    args.push_back(a);
  }
  auto r = run_relief(args, kNoMesaLeakReport);
  EXPECT_EQ(r.exit_code, 0) << r.err;
  return read_png(out, kW, kH);
}

struct Difference {
  int largest = 0;
  size_t over_one = 0;  // channels differing by more than one level
};
Difference compare(const Image& a, const Image& b) {
  Difference d;
  for (size_t i = 0; i < a.rgba.size() && i < b.rgba.size(); ++i) {
    const int e = std::abs(int(a.rgba[i]) - int(b.rgba[i]));
    d.largest = std::max(d.largest, e);
    if (e > 1) ++d.over_one;
  }
  return d;
}

size_t distinct_greys(const Image& a) {
  std::vector<bool> seen(256);
  for (size_t i = 0; i < a.rgba.size(); i += 4) seen[a.rgba[i]] = true;
  return static_cast<size_t>(std::count(seen.begin(), seen.end(), true));
}

TEST(TextureRender, DrawTimeProcessingEqualsTheOfflineStore) {
  const SarStores& s = stores();
  ScratchDir dir("texture_equal");
  // Lee r3 then the linear mapping a / (mean + 3 std) of the input's
  // statistics, on the GPU per quad; offline: the Lee store through the grey
  // map over [0, mean + 3 std] of the same statistics, the same mapping.
  // (--process-on gpu: auto would be the CPU on llvmpipe; ProcessingOnTheCpuEqualsTheGpu.)
  const Image drawn =
      render({"--texture", s.sar.string(), "--texture-op", "lee", "--texture-param", "radius=3",
              "--texture-op", "linear", "--process-on", "gpu", "--look-at", kDown},
             dir / "drawn.png");
  auto sar = tiles::Store::open(s.sar);
  ASSERT_TRUE(sar) << sar.error().message;
  const auto& st = sar->manifest().stats;
  const std::string top = fmt::format("{:.17g}", st.mean + 3 * st.stddev);
  const Image offline =
      render({"--texture", s.lee.string(), "--texture-range", "0," + top, "--look-at", kDown},
             dir / "offline.png");
  const Difference d = compare(drawn, offline);
  RecordProperty("largest", d.largest);
  // The mapping's division rounds differently (double in the operator, float
  // in the colour map): one grey level at most, rarely.
  EXPECT_LE(d.largest, 1);
  EXPECT_LT(d.over_one, 1u);
  EXPECT_GT(distinct_greys(drawn), 100u) << "a flat image would compare too easily";
  // And the filter did something: unfiltered, the image differs.
  const Image raw = render(
      {"--texture", s.sar.string(), "--texture-op", "linear", "--look-at", kDown}, dir / "raw.png");
  EXPECT_GT(compare(drawn, raw).over_one, size_t{kW * kH / 10});
}

// --process-on cpu runs the chain with the CPU kernels and composites on the
// GPU; the still equals --process-on gpu's within one grey level (the
// linear mapping divides in double on the CPU, in float on the GPU), and
// auto (the default) is one of the two.
TEST(TextureRender, ProcessingOnTheCpuEqualsTheGpu) {
  const SarStores& s = stores();
  ScratchDir dir("texture_cpu");
  auto still = [&](const std::string& where) {
    return render({"--texture", s.sar.string(), "--texture-op", "lee", "--texture-param",
                   "radius=3", "--texture-op", "linear", "--process-on", where, "--look-at", kDown},
                  dir / (where + ".png"));
  };
  const Image cpu = still("cpu"), gpu = still("gpu"), automatic = still("auto");
  const Difference d = compare(cpu, gpu);
  RecordProperty("largest", d.largest);
  EXPECT_LE(d.largest, 1);
  EXPECT_GT(distinct_greys(cpu), 100u) << "a flat image would compare too easily";
  EXPECT_TRUE(automatic.rgba == cpu.rgba || automatic.rgba == gpu.rgba);
}

TEST(TextureRender, ElevationIsOptionalForStillsAndPaths) {
  const SarStores& s = stores();
  ScratchDir dir("texture_path");
  const fs::path path = dir / "path.json", frames = dir / "frames", stats = dir / "stats.json";
  std::ofstream(path) << R"({"fps": 10, "keyframes": [
    {"time": 0, "camera": [169.4485, -19.5273, 2000, 0, -89, 0]},
    {"time": 0.2, "camera": [169.4490, -19.5270, 1500, 0, -89, 0]}]})";
  auto r =
      run_relief({"render", "--texture", s.sar.string(), "--texture-op", "lee", "--texture-param",
                  "radius=2", "--texture-colormap", "viridis", "--path", path.string(), "--mode",
                  "complete", "--size", "64x48", "-o", frames.string(), "--stats", stats.string()},
                 kNoMesaLeakReport);
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_TRUE(fs::exists(frames / "frame_00000.png"));
  EXPECT_TRUE(fs::exists(frames / "frame_00002.png"));
}

TEST(TextureRender, AnImageryStoreAsALayerEqualsImagery) {
  ScratchDir dir("texture_imagery");
  const fs::path world = dir / "world", dem = dir / "dem";
  ASSERT_EQ(run_relief({"build", data("imagery/world.rgb.tif"), "--kind", "imagery", "-o",
                        world.string(), "-q"})
                .exit_code,
            0);
  ASSERT_EQ(run_relief({"build", data("srtm/N42E001.hgt.zip"), "--kind", "elevation", "-o",
                        dem.string(), "-q"})
                .exit_code,
            0);
  const std::string cam = "1.5,42.5,20000,0,-40,0";
  const Image imagery =
      render({dem.string(), "--imagery", world.string(), "--camera", cam}, dir / "imagery.png");
  // The same store as a texture layer: composited on the GPU (alone, as it is).
  const Image layered =
      render({dem.string(), "--texture", world.string(), "--camera", cam}, dir / "layered.png");
  const Difference d = compare(imagery, layered);
  EXPECT_LE(d.largest, 2);
  RecordProperty("largest", d.largest);
}

TEST(TextureRender, BadTextureOptionsAreOneLineErrors) {
  const SarStores& s = stores();
  ScratchDir dir("texture_bad");
  const std::string out = (dir / "f.png").string(), sar = s.sar.string();
  const fs::path world = dir / "world";
  ASSERT_EQ(run_relief({"build", data("imagery/RGB.byte.tif"), "--kind", "imagery", "-o",
                        world.string(), "-q"})
                .exit_code,
            0);
  auto expect_error = [&](std::vector<std::string> args, const std::string& needle) {
    args.insert(args.begin(), "render");
    for (const std::string& a : {std::string("--look-at"), kDown, std::string("-o"), out}) {
      args.push_back(a);
    }
    auto r = run_relief(args);
    EXPECT_TRUE(is_one_line_error(r, needle)) << needle << ": " << r.err;
    EXPECT_FALSE(fs::exists(out));
  };
  expect_error({"--texture", sar, "--texture-op", "blur"}, "unknown operator 'blur'");
  expect_error({"--texture", sar, "--texture-op", "lee", "--texture-param", "radius=99"}, "radius");
  expect_error({"--texture", sar, "--texture-op", "lee", "--texture-param", "size=3"}, "size");
  expect_error({"--texture", world.string(), "--texture-op", "lee"},
               "lee needs a single-band store");
  expect_error({"--texture", sar, "--texture-param", "radius=3"},
               "--texture-param radius=3: comes before any --texture-op");
  expect_error({"--texture-op", "lee", "--texture", sar}, "comes before any --texture");
  expect_error({"--texture", sar, "--texture-range", "5,5"}, "--texture-range");
  expect_error({"--texture", sar, "--texture-opacity", "1.5"}, "--texture-opacity");
  expect_error({"--texture", sar, "--texture-op", "mean", "--texture-param", "radius=9"}, "border");
  expect_error({"--texture", sar, "--texture-colormap", "rainbow"}, "rainbow");
  expect_error({"--texture", (dir / "missing").string()}, "missing");
  expect_error({"--texture", sar, "--lens", "169.4485,-19.5273,0", "--lens-op", "linear"},
               "--lens: radius 0 m must be > 0");
  expect_error({"--texture", sar, "--lens-op", "linear"},
               "--lens-op linear: comes before any --lens");
  expect_error({"--texture", sar, "--lens", "169.4485,-19.5273,100", "--lens-op", "nope"},
               "unknown operator 'nope'");
  expect_error({"--texture", sar, "--process-on", "tpu"},
               "--process-on: unknown processing backend 'tpu' (gpu, cpu, auto)");
  expect_error({"--process-on", "cpu"}, "--process-on: there is no --texture layer to process");
  expect_error({"--texture", world.string(), "--detect"}, "--detect: needs a SAR texture layer");
  expect_error({"--texture", sar, "--detect", "--detect-level", "2"},
               "--detect-level: must be in (0, 1]");
}

// --detect draws the point targets' hints over the still and lists them in
// --stats; without it, the same still has none of the hints' colours.
TEST(TextureRender, DetectDrawsHintsAndListsThemInTheStats) {
  const SarStores& s = stores();
  ScratchDir dir("texture_detect");
  const std::vector<std::string> common = {"--texture",       s.sar.string(),
                                           "--texture-range", "0,150",
                                           "--look-at",       "169.4490,-19.5308,0,400,0,-90"};
  auto with_args = common;
  for (const std::string& a :
       {std::string("--detect"), std::string("--stats"), (dir / "s.json").string()}) {
    with_args.push_back(a);
  }
  const Image with = render(with_args, dir / "with.png");
  const Image without = render(common, dir / "without.png");
  // The hints' colours (view::HintStyle's).
  auto hint_pixels = [](const Image& image) {
    return count_colour(image, 60, 230, 90) + count_colour(image, 240, 60, 50);
  };
  EXPECT_GT(hint_pixels(with), 20u);
  EXPECT_EQ(hint_pixels(without), 0u);
  std::ifstream in(dir / "s.json");
  const std::string json((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  EXPECT_NE(json.find("\"pslr_db\""), std::string::npos) << json.substr(0, 400);
}

}  // namespace
}  // namespace relief::testing
