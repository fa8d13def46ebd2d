// `relief detect`: synthetic point targets in a georeferenced raster come out
// as GeoJSON points at their pixel centres; the analysis JSON and plot; bad
// input is a one-line error with nothing written.
#include <gtest/gtest.h>

#include <cmath>
#include <fstream>
#include <numbers>
#include <random>

#include <nlohmann/json.hpp>

#include "../ingest/gdal_reference.h"
#include "test_support.h"

namespace relief::testing {
namespace {
namespace fs = std::filesystem;
using nlohmann::json;

json read_json(const fs::path& p) {
  std::ifstream in(p);
  return json::parse(in);
}

// 200 x 150 samples of speckle with cross-shaped responses along the axes at
// (50, 40) and (150, 100); 0.001 degrees per sample from (10 E, 45 N).
// `infinities`: that many samples away from the targets are +inf.
std::string write_targets(const fs::path& dir, int infinities = 0) {
  const int w = 200, h = 150;
  std::vector<float> v(w * h);
  std::mt19937 rng(11);
  std::exponential_distribution<double> intensity(1.0);
  for (float& s : v) s = static_cast<float>(10 * std::sqrt(intensity(rng)));
  auto sinc = [](double x) {
    return x == 0 ? 1.0 : std::sin(std::numbers::pi * x) / (std::numbers::pi * x);
  };
  for (auto [cx, cy, peak] : {std::tuple{50, 40, 1000.0}, std::tuple{150, 100, 700.0}}) {
    for (int y = 0; y < h; ++y) {
      for (int x = 0; x < w; ++x) {
        v[y * w + x] +=
            static_cast<float>(peak * std::abs(sinc((x - cx) / 1.2) * sinc((y - cy) / 1.2)));
      }
    }
  }
  for (int i = 0; i < infinities; ++i) v[(10 + 7 * i) * w + 100 + i] = INFINITY;
  const std::string path = (dir / "targets.tif").string();
  const double gt[6] = {10, 0.001, 0, 45, 0, -0.001};
  write_geotiff(path, w, h, gt, v);
  return path;
}

TEST(Detect, TargetsBecomeGeoJsonPointsWithAnAnalysis) {
  ScratchDir dir("detect");
  const std::string in = write_targets(dir.path());
  const fs::path out = dir / "t.geojson", analysis = dir / "a.json", plot = dir / "a.png";
  auto r = run_relief({"detect", in, "-o", out.string(), "--analysis", analysis.string(), "--plot",
                       plot.string(), "--analyse", "150,101", "-q"});
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_NE(r.out.find("2 targets"), std::string::npos) << r.out;
  const json g = read_json(out);
  ASSERT_EQ(g["type"], "FeatureCollection");
  ASSERT_EQ(g["features"].size(), 2u);
  const int centres[2][2] = {{50, 40}, {150, 100}};
  for (int k = 0; k < 2; ++k) {
    const json& f = g["features"][k];
    EXPECT_EQ(f["properties"]["x"], centres[k][0]);
    EXPECT_EQ(f["properties"]["y"], centres[k][1]);
    EXPECT_NEAR(f["geometry"]["coordinates"][0].get<double>(), 10 + (centres[k][0] + 0.5) * 0.001,
                1e-9);
    EXPECT_NEAR(f["geometry"]["coordinates"][1].get<double>(), 45 - (centres[k][1] + 0.5) * 0.001,
                1e-9);
    auto dirs = f["properties"]["side_lobe_directions_deg"].get<std::vector<double>>();
    std::sort(dirs.begin(), dirs.end());
    EXPECT_EQ(dirs, (std::vector<double>{0, 90}));
  }
  const json a = read_json(analysis);
  EXPECT_EQ(a["target"]["x"], 150);
  EXPECT_EQ(a["axes"].size(), 2u);
  EXPECT_EQ(a["axes"][0]["db"].size(), 65u);
  EXPECT_LT(a["pslr_db"].get<double>(), 0);
  std::ifstream png(plot, std::ios::binary);
  char magic[8] = {};
  png.read(magic, 8);
  EXPECT_EQ(std::string(magic + 1, 3), "PNG");
}

// An infinite sample is no amplitude: it is nodata, neither a target nor the
// maximum the detector's levels are relative to.
TEST(Detect, InfiniteSamplesAreNodataNotTargets) {
  ScratchDir dir("detect_inf");
  const std::string in = write_targets(dir.path(), 5);
  const fs::path out = dir / "t.geojson";
  auto r = run_relief({"detect", in, "-o", out.string(), "-q"});
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_EQ(r.out.find(" inf"), std::string::npos) << r.out;
  const json g = read_json(out);
  ASSERT_EQ(g["features"].size(), 2u) << g.dump();
  for (const json& f : g["features"]) {
    ASSERT_TRUE(f["properties"]["amplitude"].is_number()) << f.dump();
    EXPECT_TRUE(std::isfinite(f["properties"]["amplitude"].get<double>()));
  }
}

TEST(Detect, BadInputsAreOneLineErrorsAndWriteNothing) {
  ScratchDir dir("detect_bad");
  const std::string in = write_targets(dir.path());
  const std::string out = (dir / "o.geojson").string(), a = (dir / "a.json").string();
  const std::string empty = (dir / "empty.tif").string();
  const double gt[6] = {0, 1, 0, 0, 0, -1};
  write_geotiff(empty, 20, 20, gt, std::vector<float>(400, NAN));
  auto expect_error = [&](std::vector<std::string> args, const std::string& needle) {
    auto r = run_relief(args);
    EXPECT_TRUE(is_one_line_error(r, needle)) << needle << ": " << r.err;
    EXPECT_FALSE(fs::exists(out));
    EXPECT_FALSE(fs::exists(a));
  };
  expect_error({"detect", (dir / "missing.tif").string(), "-o", out}, "missing.tif");
  expect_error({"detect", data("imagery/RGB.byte.tif"), "-o", out}, "3 bands");
  expect_error({"detect", empty, "-o", out}, "no positive amplitudes");
  expect_error({"detect", in, "-o", out, "--level", "2"}, "--level");
  expect_error({"detect", in, "-o", out, "--sensitivity", "0"}, "--sensitivity");
  expect_error({"detect", in, "-o", out, "--analyse", "1,x"}, "--analyse");
  expect_error({"detect", in, "-o", out, "--analysis", a, "--analyse", "5,5"}, "within 3 samples");
  expect_error({"detect", in}, "-o");
  EXPECT_TRUE(temporary_files(dir.path()).empty());
}

}  // namespace
}  // namespace relief::testing
