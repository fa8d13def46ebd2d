// `relief render` refuses impossible camera values and sizes with a one-line
// error naming the argument, before rendering or writing anything.
#include <gtest/gtest.h>

#include <fmt/format.h>
#include <nlohmann/json.hpp>

#include "relief/base/file_io.h"
#include "test_support.h"

namespace relief::testing {
namespace {
namespace fs = std::filesystem;

class RenderArgs : public ::testing::Test {
 protected:
  static void SetUpTestSuite() {
    dir_ = new ScratchDir("render_args");
    store_ = (dir_->path() / "pyr").string();
    ASSERT_EQ(run_relief({"build", data("srtm/N42E001.hgt.zip"), "--kind", "elevation", "-o",
                          store_, "--min-level", "8", "-q"})
                  .exit_code,
              0);
    whole_ = (dir_->path() / "whole").string();
    ASSERT_EQ(run_relief({"build", data("srtm/N42E001.hgt.zip"), "--kind", "elevation", "-o",
                          whole_, "-q"})
                  .exit_code,
              0);
  }
  static void TearDownTestSuite() {
    delete dir_;
    dir_ = nullptr;
  }
  static inline ScratchDir* dir_ = nullptr;
  static inline std::string store_;  // levels 8..10 (--min-level 8)
  static inline std::string whole_;  // levels 0..10
};

// A store built from level 8 down has no tiles above it: quads there draw
// no data, so the selection splits them wherever the data lies below. Where
// the whole pyramid draws levels 8 and finer, the same image.
TEST_F(RenderArgs, AStoreBuiltFromALevelDownDrawsAsTheWholePyramid) {
  for (const char* look_at : {"1.5,42.5,1500,30000,20,-35", "1.2,42.2,1000,8000,200,-20"}) {
    std::vector<std::vector<std::byte>> images;
    for (const std::string& store : {store_, whole_}) {
      const std::string out = (dir_->path() / "levels.png").string();
      auto r = run_relief({"render", store, "-o", out, "--look-at", look_at, "--size", "320x240",
                           "--stats", (dir_->path() / "levels.json").string()},
                          kNoMesaLeakReport);
      ASSERT_EQ(r.exit_code, 0) << r.err;
      auto bytes = read_file(out, kNoSizeLimit);
      ASSERT_TRUE(bytes) << bytes.error().message;
      images.push_back(std::move(*bytes));
    }
    EXPECT_EQ(images[0], images[1]) << look_at;
  }
}

TEST_F(RenderArgs, ImpossibleCameraValuesNameTheArgument) {
  const std::string out = (dir_->path() / "frame.png").string();
  struct Case {
    std::vector<std::string> args;
    std::string needle;
  };
  const std::vector<Case> cases = {
      {{"--look-at", "1.5,200,1000,20000,0,-30"}, "--look-at: latitude 200"},
      {{"--look-at", "1.5,-91,1000,20000,0,-30"}, "--look-at: latitude -91"},
      {{"--look-at", "400,42.5,1000,20000,0,-30"}, "--look-at: longitude 400"},
      {{"--look-at", "360,42.5,1000,20000,0,-30"}, "--look-at: longitude 360"},
      {{"--look-at", "-181,42.5,1000,20000,0,-30"}, "--look-at: longitude -181"},
      {{"--look-at", "1.5,42.5,1000,-20000,0,-30"}, "--look-at: range"},
      {{"--look-at", "1.5,42.5,1000,1e12,0,-30"}, "--look-at: range"},
      {{"--look-at", "1.5,42.5,1000,20000,0,-120"}, "--look-at: pitch"},
      {{"--look-at", "1.5,42.5,1000,20000,1e9,-30"}, "--look-at: heading"},
      {{"--look-at", "nan,42.5,1000,20000,0,-30"}, "--look-at"},
      {{"--camera", "1.5,200,5000,0,-30,0"}, "--camera: latitude 200"},
      {{"--camera", "1.5,42.5,1e30,0,-30,0"}, "--camera: height"},
      {{"--camera", "1.5,42.5,5000,0,-300,0"}, "--camera: pitch -300"},
      {{"--camera", "1.5,42.5,5000,0,-30,720"}, "--camera: roll 720"},
      {{"--camera", "1.5,42.5,inf,0,-30,0"}, "--camera"},
      {{"--camera", "1.5,42.5,5000,0,-30,0", "--fov", "0"}, "--fov"},
      {{"--camera", "1.5,42.5,5000,0,-30,0", "--fov", "180"}, "--fov"},
      {{"--camera", "1.5,42.5,5000,0,-30,0", "--fov", "nan"}, "--fov"},
      {{"--camera", "1.5,42.5,5000,0,-30,0", "--size", "0x0"}, "--size"},
      {{"--camera", "1.5,42.5,5000,0,-30,0", "--size", "100000x100000"}, "--size"},
      {{"--camera", "1.5,42.5,5000,0,-30,0", "--loader-nice", "20"}, "--loader-nice"},
      {{"--camera", "1.5,42.5,5000,0,-30,0", "--loader-nice", "-1"}, "--loader-nice"},
      {{"--camera", "1.5,42.5,5000,0,-30,0", "--refine-threads", "65"}, "--refine-threads"},
      {{"--camera", "1.5,42.5,5000,0,-30,0", "--refine-threads", "-1"}, "--refine-threads"},
      {{"--camera", "1.5,42.5,5000,0,-30,0", "--refine-threads", "two"}, "--refine-threads"},
      {{"--camera", "1.5,42.5,5000,0,-30,0", "--error-samples", "5"},
       "--error-samples: only with --stats"},
      {{"--camera", "1.5,42.5,5000,0,-30,0", "--error-samples", "-1", "--stats",
        (dir_->path() / "never.json").string()},
       "--error-samples"},
  };
  for (const auto& c : cases) {
    std::vector<std::string> args = {"render", store_, "-o", out};
    args.insert(args.end(), c.args.begin(), c.args.end());
    if (c.needle != "--size") args.insert(args.end(), {"--size", "32x24"});
    auto r = run_relief(args, kNoMesaLeakReport);
    EXPECT_TRUE(is_one_line_error(r, c.needle))
        << c.args.front() << " " << c.args[1] << ": exit " << r.exit_code << ", " << r.err;
  }
  EXPECT_FALSE(fs::exists(out));
  EXPECT_FALSE(fs::exists(dir_->path() / "never.json"));
}

// The refinement in lanes makes the mesh of one thread, and so does the
// one whose split criteria the GL compute shader evaluates: the same image.
TEST_F(RenderArgs, RefineThreadsAndTheGlCriteriaDrawTheSameImage) {
  std::vector<std::vector<std::byte>> images;
  const std::vector<std::vector<std::string>> runs = {
      {"--refine-threads", "1"}, {"--refine-threads", "3"}, {"--lod", "edge-marks-gl"}};
  for (size_t i = 0; i < runs.size(); ++i) {
    const std::string out = (dir_->path() / fmt::format("refined-{}.png", i)).string();
    std::vector<std::string> args = {"render", store_,      "-o",
                                     out,      "--look-at", "1.5,42.5,1500,30000,20,-35",
                                     "--size", "320x240"};
    args.insert(args.end(), runs[i].begin(), runs[i].end());
    auto r = run_relief(args, kNoMesaLeakReport);
    ASSERT_EQ(r.exit_code, 0) << r.err;
    auto bytes = read_file(out, kNoSizeLimit);
    ASSERT_TRUE(bytes) << bytes.error().message;
    images.push_back(std::move(*bytes));
  }
  ASSERT_GT(images[0].size(), 1000u);
  EXPECT_EQ(images[0], images[1]);
  EXPECT_EQ(images[0], images[2]);
}

// A still's statistics measure 20 000 finest samples, or --error-samples.
TEST_F(RenderArgs, ErrorSamplesSetTheStillsMeasurement) {
  for (const char* n : {"", "0", "30"}) {
    const std::string out = (dir_->path() / "samples.png").string();
    const std::string stats = (dir_->path() / "samples.json").string();
    std::vector<std::string> args = {
        "render", store_,    "-o",      out,  "--look-at", "1.5,42.5,1500,30000,20,-35",
        "--size", "160x120", "--stats", stats};
    if (*n) args.insert(args.end(), {"--error-samples", n});
    auto r = run_relief(args, kNoMesaLeakReport);
    ASSERT_EQ(r.exit_code, 0) << r.err;
    auto text = read_file(stats, kNoSizeLimit);
    ASSERT_TRUE(text) << text.error().message;
    const auto json = nlohmann::json::parse(
        std::string(reinterpret_cast<const char*>(text->data()), text->size()));
    if (std::string(n) == "0") {
      EXPECT_FALSE(json.contains("measured_error"));
    } else {
      const int samples = json["measured_error"]["samples"].get<int>();
      EXPECT_GT(samples, 0);
      EXPECT_LE(samples, *n ? 30 : 20000);
      if (!*n) {
        EXPECT_GT(samples, 30);
      }
    }
  }
}

TEST_F(RenderArgs, AnUnknownLodModeNamesTheModes) {
  const std::string out = (dir_->path() / "lod.png").string();
  auto r = run_relief({"render", store_, "-o", out, "--size", "32x24", "--lod", "edge-marks-gpu"},
                      kNoMesaLeakReport);
  EXPECT_TRUE(is_one_line_error(r, "--lod: 'edge-marks-gpu' is none of")) << r.err;
  EXPECT_NE(r.err.find("edge-marks-gl"), std::string::npos) << r.err;
  EXPECT_FALSE(fs::exists(out));
}

}  // namespace
}  // namespace relief::testing
