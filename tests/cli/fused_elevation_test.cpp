// `relief render STORE --elevation STORE2 [--fuse first|mean]`: elevation
// layers fused at draw time (docs/rendering.md). N41E001 and N42E001 built as
// two stores and fused while drawing give the still of the store built from
// both files; bad layers are one-line errors.
#include <gtest/gtest.h>

#include <cstdlib>
#include <sstream>

#include "images.h"
#include "test_support.h"

namespace relief::testing {
namespace {

class FusedElevation : public ::testing::Test {
 protected:
  static void SetUpTestSuite() {
    dir_ = new ScratchDir("fused_elevation");
    for (auto [name, files] :
         {std::pair<std::string, std::vector<std::string>>{"n41", {"srtm/N41E001.hgt.zip"}},
          {"n42", {"srtm/N42E001.hgt.zip"}},
          {"pair", {"srtm/N41E001.hgt.zip", "srtm/N42E001.hgt.zip"}}}) {
      std::vector<std::string> args = {"build", "--kind", "elevation", "-q", "-o", path(name)};
      for (const auto& f : files) args.push_back(data(f));
      ASSERT_EQ(run_relief(args).exit_code, 0) << name;
    }
    // Three levels short of the others' finest: a coarse layer around N42E001.
    ASSERT_EQ(run_relief({"build", "--kind", "elevation", "-q", "-o", path("coarse"), "--max-level",
                          "7", data("srtm/N41E001.hgt.zip"), data("srtm/N42E001.hgt.zip")})
                  .exit_code,
              0);
    ASSERT_EQ(run_relief({"build", "--kind", "imagery", "-q", "-o", path("rgb"),
                          data("imagery/RGB.byte.tif")})
                  .exit_code,
              0);
  }
  static void TearDownTestSuite() {
    delete dir_;
    dir_ = nullptr;
  }
  static std::string path(const std::string& name) { return (dir_->path() / name).string(); }

  static Image render(std::vector<std::string> stores, const std::string& camera,
                      const std::string& out) {
    std::vector<std::string> args = {"render"};
    args.insert(args.end(), stores.begin(), stores.end());
    for (const char* a : {"--look-at", camera.c_str(), "--size", "480x320"}) args.push_back(a);
    args.push_back("-o");
    args.push_back(path(out));
    const RunResult r = run_relief(args, kNoMesaLeakReport);
    EXPECT_EQ(r.exit_code, 0) << r.err;
    return read_png(path(out), 480, 320);
  }

  static inline ScratchDir* dir_ = nullptr;
};

// The fused finest tiles are the pair's (the files overlap by one row at
// 42°N with equal values); coarser tiles differ only next to 42°N, where the
// pair's were averaged from both files and each layer's from its own (the
// fused coarse tile takes N41's sample there, averaged over fewer finest
// samples). So the frames agree but for a few pixels shaded from those rows.
TEST_F(FusedElevation, TwoLayersDrawTheStillOfTheStoreBuiltFromBoth) {
  struct Case {
    std::string camera;
    std::vector<std::string> layers;
  };
  // Oblique across 42N, first valid; straight down over both, the mean in
  // the other order.
  const Case cases[] = {
      {"1.5,42.0,1000,60000,0,-40", {path("n41"), "--elevation", path("n42")}},
      {"1.5,42.0,1000,150000,0,-89", {path("n42"), "--elevation", path("n41"), "--fuse", "mean"}},
  };
  for (const Case& c : cases) {
    const Image built = render({path("pair")}, c.camera, "pair.png");
    const Image fused = render(c.layers, c.camera, "fused.png");
    size_t off = 0, off_more = 0;
    for (size_t i = 0; i < built.rgba.size(); ++i) {
      const int d = std::abs(int(built.rgba[i]) - int(fused.rgba[i]));
      off += d > 0;
      off_more += d > 1;
    }
    const double channels = 480.0 * 320 * 4;
    EXPECT_LE(off / channels, 0.002) << c.camera << ": " << off << " channels differ";
    EXPECT_LE(off_more / channels, 0.001) << c.camera << ": " << off_more << " off by > 1";
  }
}

// `--fuse mean --weights 3,1` draws the still of the store `relief fuse
// --weights 3,1` writes from the same two stores, pixel for pixel: the same
// samples and geometric errors (tests/pipeline/fused_elevation_test.cpp);
// only the index bounds differ (the offline store's come from its inputs'
// indexes, the draw-time ones from the fused samples), and not so as to
// change this view's quads.
TEST_F(FusedElevation, WeightedLayersDrawTheStillOfReliefFuseWeights) {
  ASSERT_EQ(run_relief(
                {"fuse", path("n41"), path("n42"), "--weights", "3,1", "-q", "-o", path("fused31")})
                .exit_code,
            0);
  const std::string camera = "1.5,42.0,1000,60000,0,-40";
  const Image offline = render({path("fused31")}, camera, "offline31.png");
  const Image drawn =
      render({path("n41"), "--elevation", path("n42"), "--fuse", "mean", "--weights", "3,1"},
             camera, "drawn31.png");
  size_t off = 0;
  for (size_t i = 0; i < offline.rgba.size(); ++i) off += offline.rgba[i] != drawn.rgba[i];
  EXPECT_EQ(off, 0u) << off << " channels differ";
}

TEST_F(FusedElevation, BadLayersAreOneLineErrors) {
  const std::string out = path("bad.png");
  const std::string cam = "1.5,42.0,1000,60000,0,-40";
  struct Case {
    std::vector<std::string> args;
    std::string needle;
  };
  const std::vector<Case> cases = {
      {{path("n41"), "--elevation", path("rgb")}, "--elevation must be an elevation store"},
      {{path("n41"), "--elevation", path("missing")}, "missing"},
      {{path("n41"), "--elevation", path("n42"), "--fuse", "max"}, "--fuse: 'max' is none of"},
      {{path("n41"), "--elevation", path("n42"), "--fuse", "mean", "--weights", "1"},
       "--weights: 1 weights for 2 elevation layers"},
      {{path("n41"), "--elevation", path("n42"), "--fuse", "mean", "--weights", "1,2,3"},
       "--weights: 3 weights for 2 elevation layers"},
      {{path("n41"), "--elevation", path("n42"), "--fuse", "mean", "--weights", "1,-2"},
       "--weights: -2 is not > 0"},
      {{path("n41"), "--elevation", path("n42"), "--fuse", "mean", "--weights", "0,0"},
       "--weights: 0 is not > 0"},
      {{path("n41"), "--elevation", path("n42"), "--fuse", "mean", "--weights", "1,inf"},
       "--weights: 'inf' is not a number"},
      {{path("n41"), "--elevation", path("n42"), "--fuse", "mean", "--weights", "1,nan"},
       "--weights: 'nan' is not a number"},
      {{path("n41"), "--elevation", path("n42"), "--weights", "1,2"}, "give --fuse mean"},
      {{path("n41"), "--elevation", path("n42"), "--fuse", "first", "--weights", "1,2"},
       "give --fuse mean"},
  };
  for (const Case& c : cases) {
    std::vector<std::string> args = {"render"};
    args.insert(args.end(), c.args.begin(), c.args.end());
    for (const std::string& a : {std::string("--look-at"), cam, std::string("-o"), out}) {
      args.push_back(a);
    }
    const RunResult r = run_relief(args, kNoMesaLeakReport);
    EXPECT_NE(r.exit_code, 0);
    EXPECT_TRUE(is_one_line_error(r, c.needle)) << r.err;
    EXPECT_FALSE(std::filesystem::exists(out));
  }
}

// Layers of different depths (a coarse layer with a fine one inside it, as
// ETOPO5 with the Pyrenees): the coarse layer first, as the README's flight
// gives them. Drawn with edge marks (the default) and with --lod quads, the
// still is the pair's where the fine layer is (north of 42N, the far half of
// this view) and far closer to it than the coarse layer alone. (Edge marks
// split quads by the level errors, which differ between the two stores: the
// fused one's count the coarse layer's ground too. Quads of other levels
// shade from other tiles, so the margin is wider: measured 0.25 of the
// coarse layer's difference, against 0.05 with quads.)
TEST_F(FusedElevation, ACoarseLayerWithAFineOneInsideDrawsASaneStill) {
  const std::string camera = "1.5,42.0,1000,60000,0,-40";
  for (const std::string lod : {"edge-marks", "quads"}) {
    SCOPED_TRACE(lod);
    auto with_lod = [&lod](std::vector<std::string> layers) {
      layers.push_back("--lod");
      layers.push_back(lod);
      return layers;
    };
    const Image pair = render(with_lod({path("pair")}), camera, "pair-" + lod + ".png");
    const Image coarse = render(with_lod({path("coarse")}), camera, "coarse-" + lod + ".png");
    const Image fused = render(with_lod({path("coarse"), "--elevation", path("n42")}), camera,
                               "sparse-" + lod + ".png");
    // Mean absolute difference over the far (upper) half: north of 42N.
    auto far_difference = [](const Image& a, const Image& b) {
      double sum = 0;
      const size_t half = a.rgba.size() / 2;
      for (size_t i = 0; i < half; ++i) sum += std::abs(int(a.rgba[i]) - int(b.rgba[i]));
      return sum / double(half);
    };
    const double to_pair = far_difference(fused, pair),
                 coarse_to_pair = far_difference(coarse, pair);
    EXPECT_LT(to_pair, (lod == "quads" ? 0.25 : 0.33) * coarse_to_pair)
        << to_pair << " against " << coarse_to_pair;
    EXPECT_LT(to_pair, 1.0);
  }
}

// No crack where the data level changes (the fine layer's edge at 42N, the
// padding around it): views that see only ground (pitch below -fov/2) over a
// magenta sky show no magenta pixel, with either LOD mode.
TEST_F(FusedElevation, NoCracksWhereTheFineLayerEnds) {
  const double views[][5] = {{1.45, 42.02, 3600, 20, -50},
                             {1.62, 41.98, 4200, 135, -40},
                             {1.30, 42.05, 3800, 250, -65},
                             {1.75, 41.95, 3500, 310, -38},
                             {1.55, 42.10, 5000, 180, -45}};
  int n = 0;
  for (const char* lod : {"quads", "edge-marks"}) {
    for (const auto& v : views) {
      std::ostringstream camera_text;
      camera_text << v[0] << ',' << v[1] << ',' << v[2] << ',' << v[3] << ',' << v[4] << ",0";
      const std::string camera = camera_text.str();
      const std::string out = path("crack" + std::to_string(n++) + ".png");
      const RunResult r = run_relief(
          {"render", path("coarse"), "--elevation", path("n42"), "--lod", lod, "--camera", camera,
           "--sky", "255,0,255", "--pixel-error", "1.5", "--size", "240x180", "-o", out},
          kNoMesaLeakReport);
      ASSERT_EQ(r.exit_code, 0) << r.err;
      EXPECT_EQ(count_colour(read_png(out, 240, 180), 255, 0, 255), 0u) << lod << " " << camera;
    }
  }
}

}  // namespace
}  // namespace relief::testing
