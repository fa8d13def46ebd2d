// `mpirun -n K relief render ... --parallel MODE` against one process's
// image of the same view: sort-first tiles and sort-last depth compositing
// for 2, 3 and 4 ranks, display walls, the load balance of the quad
// decompositions, a rank that dies or hangs, bad modes.
#include <gtest/gtest.h>

#include <fstream>

#include <fmt/format.h>
#include <nlohmann/json.hpp>

#include "images.h"
#include "relief/base/file_io.h"
#include "test_support.h"

namespace relief::testing {
namespace {
namespace fs = std::filesystem;

constexpr int kWidth = 320, kHeight = 240;
const std::vector<std::string> kView = {"--look-at", "1.5,42.5,1500,40000,0,-30"};

class Stores : public ::testing::Environment {
 public:
  static fs::path pyrenees() { return dir() / "pyrenees"; }
  static fs::path dir() {
    static ScratchDir d("parallel_stores");
    return d.path();
  }
  void SetUp() override {
    ASSERT_EQ(run_relief({"build", data("srtm/N41E001.hgt.zip"), data("srtm/N42E001.hgt.zip"),
                          "--kind", "elevation", "-o", pyrenees().string(), "-q"})
                  .exit_code,
              0);
  }
};
const auto* const kStores = ::testing::AddGlobalTestEnvironment(new Stores);

// mpirun as root needs its consent; llvmpipe's leak at unload is not ours.
std::string mpirun(int ranks, const std::string& env = "") {
  return fmt::format(
      "{}OMPI_ALLOW_RUN_AS_ROOT=1 OMPI_ALLOW_RUN_AS_ROOT_CONFIRM=1 {} {} --oversubscribe -n {}",
      kNoMesaLeakReport, env, RELIEF_MPIEXEC, ranks);
}

std::vector<std::string> render_args(const fs::path& out, int w = kWidth, int h = kHeight) {
  std::vector<std::string> a = {"render", Stores::pyrenees().string(), "-o", out.string()};
  if (w) a.insert(a.end(), {"--size", fmt::format("{}x{}", w, h)});
  a.insert(a.end(), kView.begin(), kView.end());
  return a;
}

// One process's image of the view (the reference), rendered once per size.
const Image& single(int w = kWidth, int h = kHeight) {
  static std::map<std::pair<int, int>, Image> done;
  auto [it, fresh] = done.try_emplace({w, h});
  if (fresh) {
    const fs::path out = Stores::dir() / fmt::format("single_{}x{}.png", w, h);
    auto r = run_relief(render_args(out, w, h), kNoMesaLeakReport);
    EXPECT_EQ(r.exit_code, 0) << r.err;
    it->second = read_png(out, w, h);
  }
  return it->second;
}

size_t differing_pixels(const Image& a, const Image& b) {
  size_t n = 0;
  for (size_t i = 0; i + 3 < a.rgba.size() && i + 3 < b.rgba.size(); i += 4) {
    n += !std::equal(&a.rgba[i], &a.rgba[i] + 4, &b.rgba[i]);
  }
  return n;
}

// Sort-first tiles and wall displays draw through a viewport shifted by
// their window's origin: the same clip coordinates as the whole image, but
// the rasteriser's viewport transform rounds differently (a 1/256 pixel snap
// now and then), so a few interpolated colours differ by one level. The
// tolerance: no channel off by more than 1, at most 0.2 % of the pixels.
void expect_near(const Image& a, const Image& b, const std::string& what) {
  size_t differing = 0;
  int worst = 0;
  for (size_t i = 0; i < a.rgba.size() && i < b.rgba.size(); i += 4) {
    int d = 0;
    for (size_t c = 0; c < 4; ++c)
      d = std::max(d, std::abs(int(a.rgba[i + c]) - int(b.rgba[i + c])));
    differing += d > 0;
    worst = std::max(worst, d);
  }
  EXPECT_LE(worst, 1) << what;
  EXPECT_LE(differing, a.rgba.size() / 4 / 500) << what;
}

RunResult parallel_render(int ranks, const std::string& mode, const fs::path& out,
                          std::vector<std::string> extra = {}) {
  std::vector<std::string> a = render_args(out);
  a.insert(a.end(), {"--parallel", mode, "--parallel-timeout", "120"});
  a.insert(a.end(), extra.begin(), extra.end());
  return run_relief(a, mpirun(ranks));
}

class EveryMode : public ::testing::TestWithParam<const char*> {};

TEST_P(EveryMode, MatchesTheSingleProcessImageOn2To4Ranks) {
  ScratchDir dir("parallel_mode");
  for (int ranks : {2, 3, 4}) {
    const fs::path out = dir / fmt::format("{}.png", ranks);
    auto r = parallel_render(ranks, GetParam(), out);
    ASSERT_EQ(r.exit_code, 0) << r.err;
    const Image image = read_png(out, kWidth, kHeight);
    const std::string what = fmt::format("{} on {} ranks", GetParam(), ranks);
    if (std::string(GetParam()).starts_with("sort-last")) {
      // Disjoint subsets of the same triangles through the same viewport: exact.
      EXPECT_EQ(differing_pixels(image, single()), 0u) << what;
    } else {
      expect_near(image, single(), what);
    }
  }
}

INSTANTIATE_TEST_SUITE_P(Parallel, EveryMode,
                         ::testing::Values("sort-first:h", "sort-first:v", "sort-first:grid",
                                           "sort-last:block", "sort-last:quadtree",
                                           "sort-last:active"),
                         [](const auto& param_info) {
                           std::string n = param_info.param;
                           std::replace_if(
                               n.begin(), n.end(), [](char c) { return !isalnum(c); }, '_');
                           return n;
                         });

// Every compositor (radix-k groups, binary swap, direct send; binary swap
// of 3 ranks is one round of 3) gives the single image exactly, and
// --stats names it with its rounds and keeps each rank's composite time and
// bytes.
class EveryCompositor : public ::testing::TestWithParam<const char*> {};

TEST_P(EveryCompositor, MatchesTheSingleProcessImageOn2To4Ranks) {
  ScratchDir dir("parallel_composite");
  const std::string how = GetParam();
  for (int ranks : {2, 3, 4}) {
    const fs::path out = dir / fmt::format("{}.png", ranks), stats = dir / "stats.json";
    auto r = parallel_render(ranks, "sort-last:active", out,
                             {"--composite", how, "--stats", stats.string()});
    ASSERT_EQ(r.exit_code, 0) << r.err;
    const std::string what = fmt::format("{} on {} ranks", how, ranks);
    EXPECT_EQ(differing_pixels(read_png(out, kWidth, kHeight), single()), 0u) << what;
    const auto s = nlohmann::json::parse(*read_text_file(stats, kNoSizeLimit));
    EXPECT_EQ(s["compositing"], how == "radix-k" ? "radix-k:8" : how) << what;
    int product = 1;
    for (const auto& k : s["composite_rounds"]) product *= k.get<int>();
    EXPECT_EQ(product, ranks) << what;
    for (const auto& rank : s["ranks"]) {
      EXPECT_GT(rank["bytes_sent"].get<uint64_t>(), 0u) << what;
      EXPECT_GE(rank["composite_ms"].get<double>(), 0.0) << what;
    }
  }
}

INSTANTIATE_TEST_SUITE_P(Parallel, EveryCompositor,
                         ::testing::Values("radix-k", "binary-swap", "direct-send"),
                         [](const auto& param_info) {
                           std::string n = param_info.param;
                           std::replace_if(
                               n.begin(), n.end(), [](char c) { return !isalnum(c); }, '_');
                           return n;
                         });

// One rank drawing the whole view through a window as large as the view:
// exactly today's image.
TEST(Parallel, AWholeViewWindowIsTodaysImage) {
  ScratchDir dir("parallel_one");
  auto r = parallel_render(1, "sort-first:grid", dir / "one.png");
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_EQ(differing_pixels(read_png(dir / "one.png", kWidth, kHeight), single()), 0u);
}

// A camera path, frame by frame, equals `relief render --path --mode
// complete` (sort-last: exact), with per-frame figures in --stats.
TEST(Parallel, APathEqualsTheSingleProcessFrames) {
  ScratchDir dir("parallel_path");
  const std::string path = data("paths/pyrenees-flyover.json");
  std::vector<std::string> a = {
      "render", Stores::pyrenees().string(), "--size", "160x120", "--path", path, "--fps", "1"};
  std::vector<std::string> one = a, many = a;
  one.insert(one.end(), {"--mode", "complete", "-o", (dir / "one").string()});
  ASSERT_EQ(run_relief(one, kNoMesaLeakReport).exit_code, 0);
  many.insert(many.end(), {"-o", (dir / "many").string(), "--parallel", "sort-last:active",
                           "--stats", (dir / "stats.json").string()});
  auto r = run_relief(many, mpirun(2));
  ASSERT_EQ(r.exit_code, 0) << r.err;
  for (int i = 0; i < 4; ++i) {
    const std::string name = fmt::format("frame_{:05d}.png", i);
    EXPECT_EQ(differing_pixels(read_png(dir / "many" / name, 160, 120),
                               read_png(dir / "one" / name, 160, 120)),
              0u)
        << name;
  }
  EXPECT_FALSE(fs::exists(dir / "many" / "frame_00004.png"));
  const auto stats = nlohmann::json::parse(*read_text_file(dir / "stats.json", kNoSizeLimit));
  ASSERT_EQ(stats["frames"].size(), 4u);
  EXPECT_EQ(stats["frames"][3]["ranks"].size(), 2u);
}

nlohmann::json stats_of(int ranks, const std::string& mode, ScratchDir& dir,
                        const std::string& lod = "quads") {
  const fs::path stats = dir / (mode.substr(10) + lod + ".json");
  auto r = parallel_render(ranks, mode, dir / "out.png", {"--stats", stats.string(), "--lod", lod});
  EXPECT_EQ(r.exit_code, 0) << r.err;
  return nlohmann::json::parse(*read_text_file(stats, kNoSizeLimit));
}

// With --lod quads every quad has about the same triangles, the seed's
// K-patches, each drawn whole.
TEST(Parallel, ActivePatchesBalanceTrianglesBetterThanBlocks) {
  ScratchDir dir("parallel_balance");
  const nlohmann::json active = stats_of(4, "sort-last:active", dir);
  const nlohmann::json block = stats_of(4, "sort-last:block", dir);
  ASSERT_EQ(active["ranks"].size(), 4u);
  uint64_t total = 0;
  for (const auto& rank : active["ranks"]) {
    EXPECT_GT(rank["triangles"].get<uint64_t>(), 0u);
    EXPECT_GT(rank["bytes_sent"].get<uint64_t>(), 0u);
    total += rank["triangles"].get<uint64_t>();
  }
  uint64_t block_total = 0;
  for (const auto& rank : block["ranks"]) block_total += rank["triangles"].get<uint64_t>();
  EXPECT_EQ(total, block_total);  // the same selection, split differently
  EXPECT_LT(active["triangle_imbalance"].get<double>(), 0.05);
  EXPECT_LT(active["triangle_imbalance"].get<double>(), block["triangle_imbalance"].get<double>());
}

// Edge-mark quads vary tenfold (72 of them over 4 ranks, whole, gave ~8 %
// here): active-patch enumeration splits the quads on a cut between ranks,
// so the balance is exact to a triangle, and the image stays the single
// process's (EveryMode).
TEST(Parallel, ActivePatchesSplitEdgeMarkQuadsToBalance) {
  ScratchDir dir("parallel_balance_marks");
  const nlohmann::json active = stats_of(4, "sort-last:active", dir, "edge-marks");
  ASSERT_EQ(active["ranks"].size(), 4u);
  EXPECT_LT(active["triangle_imbalance"].get<double>(), 1e-3);
}

// A 2 x 2 wall of 150 x 110 displays with bezels: each display shows its
// rectangle of the virtual view, the bezels' pixels skipped, so each image is
// the matching part of one process's image of the whole wall.
TEST(Parallel, AWallWithBezelsShowsEachDisplaysPartOfTheVirtualView) {
  ScratchDir dir("parallel_wall");
  const fs::path wall = dir / "wall.json";
  std::ofstream(wall) << R"({"rows": 2, "columns": 2, "display": [150, 110], "bezel": [20, 20],
                            "offsets": [[0, 0], [0, 0], [0, 0], [0, 0]]})";
  std::vector<std::string> a = render_args(dir / "wall.png", 0);
  a.insert(a.end(), {"--parallel", "wall:" + wall.string()});
  auto r = run_relief(a, mpirun(4));
  ASSERT_EQ(r.exit_code, 0) << r.err;
  const Image& whole = single(320, 240);  // 2 * 150 + 20, 2 * 110 + 20
  for (int row = 0; row < 2; ++row) {
    for (int col = 0; col < 2; ++col) {
      const Image d = read_png(dir / fmt::format("wall_r{}_c{}.png", row, col), 150, 110);
      Image expected{150, 110, {}};
      for (int y = 0; y < 110; ++y) {
        const size_t from = (size_t(row * 130 + y) * 320 + size_t(col * 170)) * 4;
        expected.rgba.insert(expected.rgba.end(), whole.rgba.begin() + from,
                             whole.rgba.begin() + from + 150 * 4);
      }
      expect_near(d, expected, fmt::format("display {},{}", row, col));
    }
  }
  // The wall needs one rank per display.
  auto three = run_relief(a, mpirun(3));
  EXPECT_NE(three.exit_code, 0);
  EXPECT_NE(three.err.find("has 4 displays for 3 ranks"), std::string::npos) << three.err;
}

// Sort-first gives each rank a screen tile: a view with fewer rows (h) or
// columns (v) than ranks is a one-line error before anything is drawn, not
// a rank's internal "window 1x0+0+0 is not inside the view" (issue 42).
TEST(Parallel, ASortFirstViewTooSmallForItsRanksIsAOneLineError) {
  ScratchDir dir("parallel_too_small");
  const fs::path out = dir / "out.png";
  for (const char* mode : {"sort-first:v", "sort-first:h", "sort-first:grid"}) {
    std::vector<std::string> a = render_args(out, 1, 1);
    a.insert(a.end(), {"--parallel", mode});
    auto r = run_relief(a, mpirun(2));
    EXPECT_NE(r.exit_code, 0) << mode;
    EXPECT_NE(r.err.find(fmt::format("relief: --parallel {}: a 1x1 view has too few pixels to "
                                     "give each of the 2 ranks a screen tile",
                                     mode)),
              std::string::npos)
        << r.err;
    EXPECT_EQ(r.err.find("is not inside"), std::string::npos) << r.err;
  }
  EXPECT_FALSE(fs::exists(out));
}

// A rank that dies, or stops answering, fails the run with a message
// instead of a hang (the test's own timeout would catch a hang).
TEST(Parallel, ARankThatHangsFailsTheRunWithinTheTimeout) {
  ScratchDir dir("parallel_hang");
  std::vector<std::string> a = render_args(dir / "out.png");
  a.insert(a.end(), {"--parallel", "sort-last:active", "--parallel-timeout", "3"});
  auto r = run_relief(a, mpirun(2, "RELIEF_PARALLEL_FAULT=hang:1"));
  EXPECT_NE(r.exit_code, 0);
  EXPECT_NE(r.err.find("relief: rank 0: nothing from rank 1 within 3 s (it died or hangs)"),
            std::string::npos)
      << r.err;
  EXPECT_FALSE(fs::exists(dir / "out.png"));
}

// The same during sort-last's compressed compositing: 3 ranks of radix-k
// (one round of 3) all wait for rank 2 directly; with binary swap on 4 ranks
// the ranks that finished the first round wait in the second for a rank that
// waits for the hung one, and the run still ends within the timeout.
//
// The live ranks must not be taken for hung ones: a rank still rendering its
// share while another already waits looks the same from outside. Three ranks
// on two cores beside other tests (and 5-10x slower under a sanitizer) can
// start compositing seconds apart, so the run that names the hung rank gives
// them 8 s.
TEST(Parallel, ARankThatHangsDuringRadixKFailsTheRunWithinTheTimeout) {
  ScratchDir dir("parallel_hang_radix");
  std::vector<std::string> a = render_args(dir / "out.png");
  a.insert(a.end(), {"--parallel", "sort-last:active", "--parallel-timeout", "8"});
  auto r = run_relief(a, mpirun(3, "RELIEF_PARALLEL_FAULT=hang:2"));
  EXPECT_NE(r.exit_code, 0);
  EXPECT_NE(r.err.find("nothing from rank 2 within 8 s (it died or hangs)"), std::string::npos)
      << r.err;
  a.back() = "3";  // --parallel-timeout: any rank may be named below
  a.insert(a.end(), {"--composite", "binary-swap"});
  auto swap = run_relief(a, mpirun(4, "RELIEF_PARALLEL_FAULT=hang:3"));
  EXPECT_NE(swap.exit_code, 0);
  EXPECT_NE(swap.err.find("within 3 s (it died or hangs)"), std::string::npos) << swap.err;
  EXPECT_FALSE(fs::exists(dir / "out.png"));
}

TEST(Parallel, ARankThatDiesDuringRadixKFailsTheRun) {
  ScratchDir dir("parallel_kill_radix");
  std::vector<std::string> a = render_args(dir / "out.png");
  a.insert(a.end(), {"--parallel", "sort-last:active", "--composite", "binary-swap",
                     "--parallel-timeout", "3"});
  auto r = run_relief(a, mpirun(4, "RELIEF_PARALLEL_FAULT=kill:3"));
  EXPECT_NE(r.exit_code, 0);
  EXPECT_NE(r.err.find("rank 3"), std::string::npos) << r.err;
  EXPECT_FALSE(fs::exists(dir / "out.png"));
}

TEST(Parallel, ARankThatDiesFailsTheRun) {
  ScratchDir dir("parallel_kill");
  std::vector<std::string> a = render_args(dir / "out.png");
  a.insert(a.end(), {"--parallel", "sort-first:h", "--parallel-timeout", "3"});
  auto r = run_relief(a, mpirun(3, "RELIEF_PARALLEL_FAULT=kill:2"));
  EXPECT_NE(r.exit_code, 0);
  // mpirun notices the death first and ends the run, saying which rank.
  EXPECT_NE(r.err.find("rank 2"), std::string::npos) << r.err;
  EXPECT_FALSE(fs::exists(dir / "out.png"));
}

// libmpi loads with --parallel only (the MPI module), not with every
// command: the dynamic loader's own log of the files it loads says so.
TEST(Parallel, OnlyTheParallelPathLoadsMpi) {
  ScratchDir dir("parallel_loads");
  auto info = run_relief({"info", Stores::pyrenees().string()}, "LD_DEBUG=files");
  ASSERT_EQ(info.exit_code, 0) << info.err;
  EXPECT_NE(info.err.find("libc.so"), std::string::npos);  // the log is there
  EXPECT_EQ(info.err.find("libmpi"), std::string::npos);
  std::vector<std::string> a = render_args(dir / "out.png");
  a.insert(a.end(), {"--parallel", "sort-last:active"});
  auto render = run_relief(a, kNoMesaLeakReport + "LD_DEBUG=files ");
  ASSERT_EQ(render.exit_code, 0) << render.err;
  EXPECT_NE(render.err.find("libmpi"), std::string::npos);
}

TEST(Parallel, BadModesAreOneLineErrors) {
  ScratchDir dir("parallel_bad");
  std::vector<std::string> a = render_args(dir / "out.png");
  auto with = [&](std::vector<std::string> extra) {
    std::vector<std::string> b = a;
    b.insert(b.end(), extra.begin(), extra.end());
    return run_relief(b, kNoMesaLeakReport);
  };
  EXPECT_TRUE(
      is_one_line_error(with({"--parallel", "sort-middle:h"}), "--parallel: 'sort-middle:h'"));
  EXPECT_TRUE(is_one_line_error(with({"--parallel", "sort-last:random"}), "sort-last:block"));
  EXPECT_TRUE(is_one_line_error(with({"--parallel", "sort-first:h", "--parallel-timeout", "0"}),
                                "--parallel-timeout"));
  EXPECT_TRUE(
      is_one_line_error(with({"--parallel", "wall:" + (dir / "none.json").string()}), "none.json"));
  EXPECT_TRUE(
      is_one_line_error(with({"--parallel", "sort-last:active", "--composite", "radix-k:1"}),
                        "--composite: 'radix-k:1'"));
  EXPECT_TRUE(is_one_line_error(with({"--parallel", "sort-first:h", "--composite", "radix-k"}),
                                "--composite: only with --parallel sort-last"));
  EXPECT_TRUE(is_one_line_error(with({"--composite", "radix-k"}), "--composite"));
  // A module that is not one (RELIEF_PARALLEL_MODULE names it): a one-line error.
  const fs::path bogus = dir / "not-a-module.so";
  std::ofstream(bogus) << "not ELF";
  std::vector<std::string> b = a;
  b.insert(b.end(), {"--parallel", "sort-last:active"});
  EXPECT_TRUE(is_one_line_error(
      run_relief(b, kNoMesaLeakReport + "RELIEF_PARALLEL_MODULE=" + bogus.string() + " "),
      "parallel: cannot load " + bogus.string()));
  EXPECT_FALSE(fs::exists(dir / "out.png"));
}

}  // namespace
}  // namespace relief::testing
