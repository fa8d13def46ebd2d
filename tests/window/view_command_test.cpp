// `relief view` from the command line under Xvfb: a window frame equals the
// headless still of its camera; scripted sessions (--play --exit-when-done
// --stats, --record) run without input; a corrupt tile is named; bad input is
// a one-line error.
#include <gtest/gtest.h>

#include <cmath>
#include <fstream>

#include <fmt/format.h>
#include <nlohmann/json.hpp>

#include "../support/images.h"
#include "../support/test_support.h"
#include "../video/movie_probe.h"
#include "pyrenees_view.h"

namespace relief::window {
namespace {

using nlohmann::json;
using testing::kNoMesaLeakReport;
using testing::run_relief;
using testing::ScratchDir;

double max_channel_difference(const testing::Image& a, const testing::Image& b, double* mean) {
  double worst = 0, sum = 0;
  for (size_t i = 0; i < a.rgba.size(); ++i) {
    const double d = std::abs(int{a.rgba[i]} - int{b.rgba[i]});
    worst = std::max(worst, d);
    sum += d;
  }
  *mean = sum / static_cast<double>(a.rgba.size());
  return worst;
}

TEST(ViewCommand, AWindowFrameEqualsTheHeadlessStillOfItsCamera) {
  ScratchDir dir("view_still");
  const std::string size = fmt::format("{}x{}", kWidth, kHeight);
  const auto still = dir / "still.png", shot = dir / "shot.png";
  auto r = run_relief(
      {"render", store_path(), "--look-at", kLookAt, "--size", size, "-o", still.string()},
      kNoMesaLeakReport);
  ASSERT_EQ(r.exit_code, 0) << r.err;
  // --until-complete only guards a hang: under ASan on a busy machine the
  // loaders (nice 10 below the render thread) once needed more than 30 s.
  r = run_relief({"view", store_path(), "--look-at", kLookAt, "--size", size, "--exit-when-done",
                  "--until-complete", "300", "--no-vsync", "--screenshot", shot.string()},
                 kNoMesaLeakReport);
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_NE(r.out.find("last frame complete"), std::string::npos) << r.out;
  const testing::Image a = testing::read_png(still, kWidth, kHeight);
  const testing::Image b = testing::read_png(shot, kWidth, kHeight);
  // The same renderer into the same framebuffer formats; only the GL
  // context differs (GLX in the window, EGL headless): within 2 of 255 per
  // channel.
  double mean = 0;
  EXPECT_LE(max_channel_difference(a, b, &mean), 2) << "mean " << mean;
  EXPECT_LT(mean, 0.05);
}

// The viewer with the split criteria in the compute shader (in the window's
// own GL context) draws the mesh of the CPU's refinement: the same pixels.
TEST(ViewCommand, TheSplitCriteriaOnTheGpuDrawTheFrameOfTheCpu) {
  ScratchDir dir("view_gl_criteria");
  const std::string size = fmt::format("{}x{}", kWidth, kHeight);
  std::vector<testing::Image> shots;
  for (const char* lod : {"edge-marks", "edge-marks-gl"}) {
    const auto shot = dir / (std::string(lod) + ".png"), stats = dir / (std::string(lod) + ".json");
    auto r = run_relief({"view", store_path(), "--look-at", kLookAt, "--size", size,
                         "--exit-when-done", "--until-complete", "300", "--no-vsync", "--lod", lod,
                         "--screenshot", shot.string(), "--stats", stats.string()},
                        kNoMesaLeakReport);
    ASSERT_EQ(r.exit_code, 0) << r.err;
    shots.push_back(testing::read_png(shot, kWidth, kHeight));
    std::ifstream in(stats);
    const json s = json::parse(in);
    const json& last = s["frames"].back()["refine"];
    EXPECT_EQ(last["criteria_ms"].get<double>() > 0, std::string(lod) == "edge-marks-gl") << lod;
    EXPECT_EQ(last["marks_near"].get<uint64_t>(), 0u);
  }
  double mean = 0;
  EXPECT_EQ(max_channel_difference(shots[0], shots[1], &mean), 0);
}

void write_path(const std::filesystem::path& file) {
  std::ofstream(file) << R"({"fps": 30, "keyframes": [
    {"time": 0, "camera": [1.40, 42.40, 6000, 20, -35, 0]},
    {"time": 0.6, "camera": [1.45, 42.45, 5000, 30, -30, 0]}]})";
}

json read_json(const std::filesystem::path& file) {
  std::ifstream in(file);
  return json::parse(in);
}

TEST(ViewCommand, PlaysAPathWithoutInputAndWritesTheStatisticsOfEveryFrame) {
  ScratchDir dir("view_play");
  const auto path = dir / "path.json", stats = dir / "stats.json", points = dir / "points.json";
  write_path(path);
  // The last frame measured at data points: one near the view's centre at
  // sea level (the ground there is ~1 km higher: pixels off), one off screen.
  std::ofstream(points) << "[[1.487, 42.497, 0], [1.45, 30.0, 0]]";
  auto r = run_relief(
      {"view", store_path(), "--play", path.string(), "--exit-when-done", "--stats", stats.string(),
       "--size", "160x120", "--no-vsync", "--error-points", points.string()},
      kNoMesaLeakReport);
  ASSERT_EQ(r.exit_code, 0) << r.err;
  const json s = read_json(stats);
  const json& frames = s["frames"];
  ASSERT_GE(frames.size(), 2u);
  EXPECT_EQ(s["summary"]["frames"], frames.size());
  EXPECT_TRUE(s["summary"]["path_finished"]);
  EXPECT_TRUE(s["summary"]["complete"]);
  // The first frame at the path's end: on the clock of the frames' times.
  const double end = s["summary"]["path_end"].get<double>();
  EXPECT_GT(end, 0.5);
  EXPECT_LE(end, frames.back()["time"].get<double>());
  const json& error = s["summary"]["final_error"];
  EXPECT_EQ(error["points"], 2);
  ASSERT_EQ(error["pixels"].size(), 2u);
  EXPECT_GT(error["pixels"][0].get<double>(), 5.0);
  EXPECT_TRUE(error["pixels"][1].is_null());
  EXPECT_GT(s["summary"]["fps_p50"].get<double>(), 0);
  EXPECT_EQ(s["summary"]["target_fps"], 30) << "the viewer's frame budget by default";
  EXPECT_EQ(frames[0]["camera"][0], 1.40);
  EXPECT_EQ(frames.back()["camera"][0], 1.45) << "the last frames show the path's end";
  EXPECT_GE(frames.back()["time"].get<double>(), 0.6);
  for (const json& f : frames) {
    EXPECT_TRUE(f.contains("triangles_per_pixel"));
    EXPECT_TRUE(f.contains("uploaded_bytes"));
  }
  EXPECT_GT(frames.back()["triangles"].get<uint64_t>(), 0u);
}

// The loaders' settings reach their workers: every loader thread runs
// --loader-nice levels below the render thread (as the kernel reports it;
// 10 when not given: the viewer puts its frames first), and no more workers
// prepare tiles at once than relief view allows (one less than the cores, at
// least one).
TEST(ViewCommand, TheLoadersWorkersRunAtTheirNiceAndPrepareWithinTheLimit) {
  ScratchDir dir("view_loaders");
  const auto path = dir / "path.json";
  write_path(path);
  const int cores = static_cast<int>(std::thread::hardware_concurrency());
  for (const int nice : {-1, 0, 7}) {  // -1: not given
    const auto stats = dir / fmt::format("stats{}.json", nice);
    std::vector<std::string> args = {
        "view",    store_path(),   "--play", path.string(), "--exit-when-done",
        "--stats", stats.string(), "--size", "160x120",     "--no-vsync"};
    if (nice >= 0) args.insert(args.end(), {"--loader-nice", std::to_string(nice)});
    auto r = run_relief(args, kNoMesaLeakReport);
    ASSERT_EQ(r.exit_code, 0) << r.err;
    const json loaders = read_json(stats)["summary"]["loaders"];
    const int own = loaders["render_thread_nice"].get<int>();
    ASSERT_FALSE(loaders["worker_nice"].empty()) << "no thread named relief-loader";
    const int below = nice >= 0 ? nice : 10;
    for (const json& n : loaders["worker_nice"]) EXPECT_EQ(n.get<int>(), std::min(19, own + below));
    EXPECT_EQ(loaders["max_preparing"].get<int>(), std::max(1, cores - 1));
    EXPECT_GE(loaders["most_preparing"].get<int>(), 1) << "tiles were prepared";
    EXPECT_LE(loaders["most_preparing"].get<int>(), std::max(1, cores - 1));
  }
}

// --uploads-per-frame reaches the scene: no frame of a session uploads more
// new elevation tiles than asked (the first also its root tile), and the
// session still ends complete. So does --memory-budget: the caches it bounds
// stay within it (up to the diamond errors a frame's loads bring,
// docs/streaming.md "One memory budget"). (Whether a frame has more to upload depends
// on when the loads end; SceneTest.InteractiveFramesNeverWaitAndConvergeTo-
// TheCompleteFrame holds splits back deterministically.)
TEST(ViewCommand, NoFrameUploadsMoreNewTilesThanAsked) {
  ScratchDir dir("view_uploads");
  const auto path = dir / "path.json", stats = dir / "stats.json";
  write_path(path);
  auto r = run_relief(
      {"view", store_path(), "--play", path.string(), "--exit-when-done", "--stats", stats.string(),
       "--size", "160x120", "--no-vsync", "--uploads-per-frame", "2", "--memory-budget", "128MiB"},
      kNoMesaLeakReport);
  ASSERT_EQ(r.exit_code, 0) << r.err;
  const json s = read_json(stats);
  EXPECT_TRUE(s["summary"]["complete"].get<bool>());
  EXPECT_EQ(s["summary"]["uploads_per_frame"].get<uint32_t>(), 2u);
  const uint64_t budget = uint64_t{128} << 20;
  EXPECT_EQ(s["summary"]["memory_budget_bytes"].get<uint64_t>(), budget);
  EXPECT_GT(s["summary"]["peak_rss_bytes"].get<uint64_t>(), 0u);
  for (const json& f : s["frames"]) {
    EXPECT_GT(f["cached_bytes"].get<uint64_t>(), 0u);
    EXPECT_LE(f["cached_bytes"].get<uint64_t>(), budget + budget / 4) << "frame " << f["frame"];
    EXPECT_LE(f["tiles_uploaded"].get<uint32_t>(), f["frame"].get<int>() == 0 ? 3u : 2u)
        << "frame " << f["frame"];
    EXPECT_TRUE(f.contains("uploads_deferred"));
  }
}

TEST(ViewCommand, ARecordedSessionPlaysBackThroughTheSameCameras) {
  ScratchDir dir("view_record");
  const auto path = dir / "path.json", recorded = dir / "recorded.json", stats = dir / "stats.json";
  write_path(path);
  auto r = run_relief({"view", store_path(), "--play", path.string(), "--exit-when-done",
                       "--record", recorded.string(), "--size", "160x120", "--no-vsync"},
                      kNoMesaLeakReport);
  ASSERT_EQ(r.exit_code, 0) << r.err;
  const json rec = read_json(recorded);
  const json& keys = rec["keyframes"];
  ASSERT_GE(keys.size(), 2u);
  EXPECT_EQ(rec["fps"], 30);
  EXPECT_EQ(keys[0]["camera"][0], 1.40);
  // Played back without a frame budget: the threshold is the speed's alone.
  r = run_relief({"view", store_path(), "--play", recorded.string(), "--exit-when-done", "--stats",
                  stats.string(), "--size", "160x120", "--no-vsync", "--target-fps", "0"},
                 kNoMesaLeakReport);
  ASSERT_EQ(r.exit_code, 0) << r.err;
  const json played = read_json(stats);
  const json& frames = played["frames"];
  ASSERT_GE(frames.size(), 2u);
  for (int i = 0; i < 6; ++i) {  // the first and the last camera, exactly
    EXPECT_EQ(frames[0]["camera"][i], keys[0]["camera"][i]);
    EXPECT_EQ(frames.back()["camera"][i], keys.back()["camera"][i]);
  }
  EXPECT_EQ(played["summary"]["target_fps"], 0);
  for (const json& f : frames) {
    EXPECT_EQ(f["budget_factor"], 1) << "frame " << f["frame"];
    EXPECT_DOUBLE_EQ(f["pixel_error"].get<double>(), f["speed_factor"].get<double>())
        << "frame " << f["frame"];  // times the still threshold, 1
  }
}

// A scripted session with --record and --export-movie renders what it
// recorded as a movie, through relief render --path's code: one complete
// frame per 1/fps of the recorded path, at the window's size.
TEST(ViewCommand, AScriptedSessionExportsItsRecordedPathAsAMovie) {
  ScratchDir dir("view_export");
  const auto path = dir / "path.json", recorded = dir / "recorded.json", movie = dir / "flight.mp4";
  // At 5 fps (the recording's rate, hence the movie's), to keep the movie short.
  std::ofstream(path) << R"({"fps": 5, "keyframes": [
    {"time": 0, "camera": [1.40, 42.40, 6000, 20, -35, 0]},
    {"time": 0.6, "camera": [1.45, 42.45, 5000, 30, -30, 0]}]})";
  auto r = run_relief({"view", store_path(), "--play", path.string(), "--exit-when-done",
                       "--until-complete", "0", "--record", recorded.string(), "--export-movie",
                       movie.string(), "--size", "160x120", "--no-vsync"},
                      kNoMesaLeakReport);
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_NE(r.err.find("wrote the recorded path to " + recorded.string()), std::string::npos)
      << r.err;
  const json rec = read_json(recorded);
  const json& keys = rec["keyframes"];
  ASSERT_GE(keys.size(), 2u);
  const double seconds = keys.back()["time"].get<double>() - keys[0]["time"].get<double>();
  const long frames = static_cast<long>(std::floor(seconds * rec["fps"].get<double>() + 1e-9)) + 1;
  const testing::MovieInfo info = testing::probe_movie(movie);
  EXPECT_EQ(info.frames, frames);
  EXPECT_EQ(info.width, 160);
  EXPECT_EQ(info.height, 120);
  EXPECT_EQ(info.frame_rate, "5/1");
}

// SAR processed at draw time on the bare ellipsoid (no elevation store),
// with the detector's hints: the session plays, completes and its screenshot
// shows hints.
TEST(ViewCommand, ASarLayerWithHintsAndNoElevationStore) {
  ScratchDir dir("view_sar");
  const auto sar = dir / "sar", path = dir / "path.json", stats = dir / "stats.json",
             shot = dir / "shot.png";
  ASSERT_EQ(testing::run_relief({"build", testing::data("sar/umbra_mount_yasur.tif"), "--kind",
                                 "sar", "-o", sar.string(), "-q"})
                .exit_code,
            0);
  std::ofstream(path) << R"({"fps": 5, "keyframes": [
    {"time": 0, "camera": [169.4490, -19.5308, 450, 0, -90, 0]},
    {"time": 0.4, "camera": [169.4490, -19.5308, 400, 0, -90, 0]}]})";
  auto r = run_relief({"view",
                       "--texture",
                       sar.string(),
                       "--texture-op",
                       "lee",
                       "--texture-param",
                       "radius=3",
                       "--texture-op",
                       "linear",
                       "--detect",
                       "--play",
                       path.string(),
                       "--exit-when-done",
                       "--stats",
                       stats.string(),
                       "--screenshot",
                       shot.string(),
                       "--size",
                       "320x240",
                       "--no-vsync"},
                      kNoMesaLeakReport);
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_TRUE(read_json(stats)["summary"]["complete"].get<bool>());
  const testing::Image image = testing::read_png(shot, 320, 240);
  // The hints' colours (view::HintStyle's).
  EXPECT_GT(testing::count_colour(image, 60, 230, 90) + testing::count_colour(image, 240, 60, 50),
            20u);
}

// A corrupt tile the view needs: the session goes on without it, then names
// the tile and the problem on stderr and exits non-zero (issue 42 item 6:
// it ended with 0 and said nothing), as `relief render` fails on it.
TEST(ViewCommand, ACorruptTileIsNamedAndTheSessionFails) {
  ScratchDir dir("view_corrupt_tile");
  const std::filesystem::path store = dir / "store";
  ASSERT_EQ(run_relief({"build", testing::data("srtm/N42E001.hgt.zip"), "--kind", "elevation", "-o",
                        store.string(), "-q"})
                .exit_code,
            0);
  // The finest tile under the target, its payload overwritten in the middle.
  auto opened = tiles::Store::open(store);
  ASSERT_TRUE(opened) << opened.error().message;
  const geo::TileKey key = opened->grid().locate(opened->manifest().max_level, 1.5, 42.5).tile;
  ASSERT_TRUE(opened->has_tile(key)) << key.to_string();
  const std::filesystem::path tile = opened->tile_path(key);
  {
    std::fstream f(tile, std::ios::in | std::ios::out | std::ios::binary);
    f.seekp(200);
    f.write("garbage", 7);
  }
  const std::string size = fmt::format("{}x{}", kWidth, kHeight);
  auto r = run_relief({"view", store.string(), "--look-at", "1.5,42.5,1000,5000,0,-60", "--size",
                       size, "--exit-when-done", "--until-complete", "3", "--no-vsync"},
                      kNoMesaLeakReport);
  EXPECT_NE(r.exit_code, 0) << r.out << r.err;
  EXPECT_NE(r.out.find("frames in"), std::string::npos) << r.out;
  EXPECT_TRUE(testing::is_one_line_error(r, tile.string() + ": tile payload checksum mismatch"))
      << r.err;
}

TEST(ViewCommand, BadInputIsAOneLineError) {
  ScratchDir dir("view_bad");
  const std::string store = store_path();
  auto expect_error = [](const testing::RunResult& r, const std::string& needle) {
    EXPECT_TRUE(testing::is_one_line_error(r, needle)) << r.exit_code << ": " << r.err;
  };
  // No display: points to the headless renderer.
  expect_error(run_relief({"view", store}, "env -u DISPLAY "), "relief render");
  expect_error(run_relief({"view", store, "--record", (dir / "missing" / "r.json").string()}),
               "--record");
  expect_error(run_relief({"view", store, "--stats", (dir / "missing" / "s.json").string()}),
               "--stats");
  const auto not_json = dir / "path.json";
  std::ofstream(not_json) << "fps: 30";
  expect_error(run_relief({"view", store, "--play", not_json.string()}), not_json.string());
  expect_error(run_relief({"view", store, "--error-points", not_json.string()}), "--error-points");
  const auto stats = (dir / "s.json").string();
  expect_error(run_relief({"view", store, "--error-points", not_json.string(), "--stats", stats}),
               not_json.string());
  const auto bad_point = dir / "points.json";
  std::ofstream(bad_point) << "[[1.5, 42.5, 100], [1.5, 95, 0]]";
  expect_error(run_relief({"view", store, "--error-points", bad_point.string(), "--stats", stats}),
               "point 1");
  expect_error(run_relief({"view", store, "--mode", "glider"}), "--mode");
  expect_error(run_relief({"view", store, "--target-fps", "-5"}), "--target-fps");
  expect_error(run_relief({"view", store, "--target-fps", "fast"}), "--target-fps");
  expect_error(run_relief({"view", store, "--uploads-per-frame", "-1"}), "--uploads-per-frame");
  expect_error(run_relief({"view", store, "--uploads-per-frame", "many"}), "--uploads-per-frame");
  expect_error(run_relief({"view", store, "--memory-budget", "1MiB"}), "--memory-budget");
  expect_error(run_relief({"view", store, "--memory-budget", "lots"}), "--memory-budget");
  expect_error(run_relief({"view", store, "--play", not_json.string(), "--mode", "walk"}),
               "--play");
  expect_error(run_relief({"view", store, "--export-movie", (dir / "flight.png").string()}),
               "--export-movie");
  expect_error(
      run_relief({"view", store, "--export-movie", (dir / "missing" / "flight.mp4").string()}),
      "--export-movie");
  EXPECT_FALSE(std::filesystem::exists(dir / "missing"));
}

}  // namespace
}  // namespace relief::window
