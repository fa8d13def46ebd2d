// `relief render STORE --elevation-op OP ... --elevation-lens LON,LAT,R ...`:
// elevation processed at draw time (docs/rendering.md, "Elevation operators
// and lenses at draw time"). A lens showing the raw heights inside a circle of
// smoothed ones leaves no crack at its circle (views that see only ground over
// a magenta sky show no magenta pixel, edge marks and quads); the chain
// changes the still; bad operators, parameters and lenses are one-line errors.
#include <gtest/gtest.h>

#include <cmath>
#include <numbers>
#include <sstream>

#include "images.h"
#include "test_support.h"

namespace relief::testing {
namespace {

class ElevationOps : public SmallStoreSuite {
 protected:
  static RunResult render(std::vector<std::string> extra, const std::string& out) {
    std::vector<std::string> args = {"render", store().string()};
    args.insert(args.end(), extra.begin(), extra.end());
    args.push_back("-o");
    args.push_back(out);
    return run_relief(args, kNoMesaLeakReport);
  }
  std::string path(const std::string& name) { return (scratch() / name).string(); }
};

// Smoothed heights outside, N42E001's own inside a circle over the Andorran
// mountains: a step of up to tens of metres along the circle.
const std::vector<std::string> kLens = {"--elevation-op",    "mean",
                                        "--elevation-param", "radius=6",
                                        "--elevation-lens",  "1.55,42.55,3000"};

TEST_F(ElevationOps, NoCrackAtTheLensCircle) {
  int n = 0;
  for (const char* lod : {"edge-marks", "quads"}) {
    for (const double bearing : {20.0, 135.0, 250.0, 310.0}) {
      // Look at the circle from outside across it, down enough to see only ground.
      const double a = bearing * std::numbers::pi / 180;
      const double lat = 42.55 + 3000 * std::cos(a) / 111320.0;
      const double lon =
          1.55 + 3000 * std::sin(a) / (111320.0 * std::cos(42.55 * std::numbers::pi / 180));
      std::ostringstream look;
      look << lon << ',' << lat << ",2000,7000," << std::fmod(bearing + 180, 360) << ",-50";
      const std::string out = path("lens" + std::to_string(n++) + ".png");
      std::vector<std::string> args = kLens;
      for (const std::string& a2 :
           {std::string("--look-at"), look.str(), std::string("--lod"), std::string(lod),
            std::string("--sky"), std::string("255,0,255"), std::string("--size"),
            std::string("240x180")}) {
        args.push_back(a2);
      }
      const RunResult r = render(args, out);
      ASSERT_EQ(r.exit_code, 0) << r.err;
      EXPECT_EQ(count_colour(read_png(out, 240, 180), 255, 0, 255), 0u) << lod << " " << look.str();
    }
  }
}

// The chain is drawn: a smoothed still differs from the raw one, and a lens
// of the raw heights over the whole store draws the raw still (the processed
// tiles, with their border of 2, and their errors are then the store's own):
// the same mesh, and colours off by one level at a few pixels only, where
// texture coordinates normalised by the narrower tiles round otherwise.
TEST_F(ElevationOps, TheChainChangesTheStillAndALensOverTheViewUndoesIt) {
  const std::vector<std::string> view = {"--look-at", "1.55,42.55,2000,7000,0,-50", "--size",
                                         "240x180"};
  auto still = [&](std::vector<std::string> extra, const std::string& name) {
    extra.insert(extra.end(), view.begin(), view.end());
    const RunResult r = render(extra, path(name));
    EXPECT_EQ(r.exit_code, 0) << r.err;
    return read_png(path(name), 240, 180);
  };
  const Image raw = still({}, "raw.png");
  const Image smoothed =
      still({"--elevation-op", "gauss", "--elevation-param", "radius=5"}, "smoothed.png");
  const Image undone = still({"--elevation-op", "gauss", "--elevation-param", "radius=5",
                              "--elevation-lens", "1.55,42.55,200000"},
                             "undone.png");
  size_t changed = 0, undone_off = 0, undone_off_more = 0;
  for (size_t i = 0; i < raw.rgba.size(); ++i) {
    changed += raw.rgba[i] != smoothed.rgba[i];
    undone_off += raw.rgba[i] != undone.rgba[i];
    undone_off_more += std::abs(int(raw.rgba[i]) - int(undone.rgba[i])) > 1;
  }
  EXPECT_GT(changed, raw.rgba.size() / 10);
  EXPECT_LE(undone_off, 20u);
  EXPECT_EQ(undone_off_more, 0u);
}

TEST_F(ElevationOps, BadOperatorsParametersAndLensesAreOneLineErrors) {
  const std::string out = path("bad.png");
  struct Case {
    std::vector<std::string> args;
    std::string needle;
  };
  const std::vector<Case> cases = {
      {{"--elevation-op", "nosuch"}, "--elevation-op nosuch: unknown operator 'nosuch'"},
      {{"--elevation-op", "mean", "--elevation-param", "radius=12"},
       "--elevation-op mean: --param: radius=12 is out of range [1, 9]"},
      {{"--elevation-op", "mean", "--elevation-param", "looks=2"}, "has no parameter 'looks'"},
      {{"--elevation-param", "radius=2"}, "--elevation-param radius=2: comes before any"},
      // Not valid for heights: speckle filters, conversions, tone mappings.
      {{"--elevation-op", "lee"}, "operator lee expects SAR amplitude, linear, but the store"},
      {{"--elevation-op", "amplitude-to-db"}, "operator amplitude-to-db expects"},
      {{"--elevation-op", "db-to-amplitude"}, "operator db-to-amplitude expects"},
      {{"--elevation-op", "linear"}, "operator linear expects"},
      {{"--elevation-op", "drago"}, "operator drago expects"},
      {{"--elevation-op", "gauss", "--elevation-op", "ext-schlick"},
       "operator ext-schlick expects"},
      // Wider than the store's 9-sample border.
      {{"--elevation-op", "median", "--elevation-param", "radius=9"},
       "median: needs a 9-sample margin"},
      {{"--elevation-lens", "1.5,42.5,0"}, "--elevation-lens: radius 0 m must be > 0"},
      {{"--elevation-lens", "1.5,42.5,-20"}, "--elevation-lens: radius -20 m must be > 0"},
      {{"--elevation-lens", "1.5,42.5"}, "--elevation-lens"},
      {{"--elevation-lens", "1.5,95,100"}, "is not a longitude, latitude"},
      {{"--elevation-lens-op", "mean"}, "--elevation-lens-op mean: comes before any"},
      {{"--elevation-lens", "1.5,42.5,500", "--elevation-lens-param", "radius=2"},
       "comes before any --elevation-lens-op"},
      {{"--elevation-lens", "1.5,42.5,500", "--elevation-lens-op", "kuan"},
       "(elevation lens): operator kuan expects"},
      {{"--elevation-lens", "1.5,42.5,500", "--elevation-lens-op", "gauss",
        "--elevation-lens-param", "radius=9"},
       "(elevation lens): gauss: needs a 9-sample margin"},
      {{"--elevation-op", "mean", "--parallel", "sort-first:h"},
       "--parallel: not with --elevation-op yet"},
  };
  for (const Case& c : cases) {
    std::vector<std::string> args = c.args;
    args.push_back("--look-at");
    args.push_back("1.55,42.55,2000,7000,0,-50");
    const RunResult r = render(args, out);
    EXPECT_NE(r.exit_code, 0) << c.needle;
    EXPECT_TRUE(is_one_line_error(r, c.needle)) << c.needle << ": " << r.err;
    EXPECT_FALSE(std::filesystem::exists(out));
  }
}

TEST_F(ElevationOps, TheHelpNamesTheOptions) {
  for (const char* command : {"render", "view"}) {
    const RunResult r = run_relief({command, "--help"});
    EXPECT_EQ(r.exit_code, 0);
    for (const char* option : {"--elevation-op OP", "--elevation-param K=V",
                               "--elevation-lens LON,LAT,RADIUS_M", "mean, gauss or median"}) {
      EXPECT_NE(r.out.find(option), std::string::npos) << command << " lacks " << option;
    }
  }
}

}  // namespace
}  // namespace relief::testing
