// `relief render STORE --path PATH.json -o MOVIE.mp4` end to end: the movie
// has the path's frames, size and duration and its frames match the PNGs of
// the same path; bad input fails with one-line errors and leaves no movie
// (nor a temporary file) behind, also when the disk fills half way.
#include <gtest/gtest.h>

#include <signal.h>
#include <sys/wait.h>

#include <chrono>
#include <fstream>
#include <thread>

#include <fmt/format.h>
#include <nlohmann/json.hpp>

#include "movie_probe.h"
#include "test_support.h"

namespace relief::testing {
namespace {

namespace fs = std::filesystem;

constexpr int kWidth = 320, kHeight = 240;

class MovieTest : public ::testing::Test {
 protected:
  static void SetUpTestSuite() {
    dir_ = new ScratchDir("movie_cli");
    ASSERT_EQ(run_relief({"build", data("srtm/N42E001.hgt.zip"), "--kind", "elevation", "-o",
                          store().string(), "--tile-size", "128x64", "-q"})
                  .exit_code,
              0);
    // Half a second over the ground, turning and descending; 10 fps in the file.
    std::ofstream(path_file())
        << R"({"fps": 10, "keyframes": [{"time": 0, "camera": [1.45, 42.55, 3600, 20, -50, 0]},
              {"time": 0.5, "camera": [1.47, 42.57, 3200, 50, -40, 0]}]})";
  }
  static void TearDownTestSuite() { delete dir_; }
  static fs::path store() { return dir_->path() / "store"; }
  static fs::path path_file() { return dir_->path() / "path.json"; }
  static fs::path scratch(const std::string& name) { return dir_->path() / name; }

  static RunResult render(const fs::path& out, std::vector<std::string> extra = {},
                          const std::string& shell_prefix = "") {
    std::vector<std::string> args = {"render",       store().string(),
                                     "--path",       path_file().string(),
                                     "-o",           out.string(),
                                     "--size",       fmt::format("{}x{}", kWidth, kHeight),
                                     "--mesh-level", "3"};
    args.insert(args.end(), extra.begin(), extra.end());
    return run_relief(args, shell_prefix + kNoMesaLeakReport);
  }

  // A failed run: one line on stderr naming `needle`, no movie, no temporary.
  static void expect_refused(const RunResult& r, const std::string& needle, const fs::path& movie) {
    EXPECT_TRUE(is_one_line_error(r, needle)) << "exit " << r.exit_code << ": " << r.err;
    EXPECT_FALSE(fs::exists(movie)) << movie;
    EXPECT_TRUE(temporary_files(dir_->path()).empty());
  }

  static inline ScratchDir* dir_ = nullptr;
};

TEST_F(MovieTest, MovieHasThePathsFramesAndMatchesItsPngs) {
  // --fps overrides the file's 10: 0.5 s at 20 fps is 11 frames.
  const fs::path movie = scratch("flight.mp4"), pngs = scratch("pngs");
  const RunResult r = render(movie, {"--fps", "20", "--stats", scratch("stats.json").string()});
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_NE(r.out.find("wrote " + movie.string()), std::string::npos) << r.out;
  const MovieInfo info = probe_movie(movie);
  EXPECT_EQ(info.codec, "h264");
  EXPECT_EQ(info.pix_fmt, "yuv420p");
  EXPECT_EQ(info.width, kWidth);
  EXPECT_EQ(info.height, kHeight);
  EXPECT_EQ(info.frames, 11);
  EXPECT_EQ(info.frame_rate, "20/1");
  EXPECT_NEAR(info.duration, 11 / 20.0, 1e-3);
  std::ifstream in(scratch("stats.json"));
  const nlohmann::json stats = nlohmann::json::parse(in);
  EXPECT_EQ(stats["summary"]["mode"], "complete");  // a movie's frames are complete
  EXPECT_EQ(stats["summary"]["movie"]["frames"], 11);
  EXPECT_EQ(stats["summary"]["movie"]["crf"], 18);
  EXPECT_EQ(stats["summary"]["movie"]["preset"], "veryfast");

  const RunResult p = render(pngs, {"--fps", "20", "--mode", "complete"});
  ASSERT_EQ(p.exit_code, 0) << p.err;
  const std::vector<Image> decoded = decode_movie(movie, kWidth, kHeight);
  ASSERT_EQ(decoded.size(), 11u);
  for (size_t i = 0; i < decoded.size(); ++i) {
    const Image png = read_png(pngs / fmt::format("frame_{:05d}.png", i), kWidth, kHeight);
    EXPECT_GE(psnr(decoded[i], png), 40) << "frame " << i;
  }
}

// Over a link (here a simulated one), the export prefetches the path ahead
// on the loaders' threads and waits for each frame's tiles: the movie is the
// one made with every frame reading its tiles (--no-prefetch), frame for frame.
TEST_F(MovieTest, OverALinkThePathIsPrefetchedAndTheFramesAreTheSame) {
  const fs::path fetched = scratch("fetched.mp4"), read = scratch("read.mp4");
  const fs::path stats = scratch("fetched.json");
  const std::vector<std::string> link = {"--simulate-latency", "2"};
  std::vector<std::string> extra = link;
  extra.insert(extra.end(), {"--stats", stats.string()});
  RunResult r = render(fetched, extra);
  ASSERT_EQ(r.exit_code, 0) << r.err;
  extra = link;
  extra.push_back("--no-prefetch");
  r = render(read, extra);
  ASSERT_EQ(r.exit_code, 0) << r.err;
  std::ifstream in(stats);
  const nlohmann::json s = nlohmann::json::parse(in)["summary"];
  EXPECT_EQ(s["mode"], "complete");
  EXPECT_TRUE(s["complete"]);
  EXPECT_GT(s["prefetched"].get<uint64_t>(), 0u) << "the path ahead was prefetched";
  EXPECT_GT(s["prefetch_used"].get<uint64_t>(), 0u);
  const std::vector<Image> a = decode_movie(fetched, kWidth, kHeight);
  const std::vector<Image> b = decode_movie(read, kWidth, kHeight);
  ASSERT_EQ(a.size(), 6u);
  ASSERT_EQ(b.size(), a.size());
  for (size_t i = 0; i < a.size(); ++i) EXPECT_TRUE(a[i].rgba == b[i].rgba) << "frame " << i;
}

TEST_F(MovieTest, BadInputIsAOneLineErrorAndNoMovie) {
  const fs::path movie = scratch("bad.mp4");
  expect_refused(render(movie, {"--mode", "interactive"}), "--mode interactive", movie);
  expect_refused(render(movie, {"--size", "321x240"}), "--size: 321x240", movie);
  expect_refused(render(movie, {"--codec", "prores"}), "--codec: 'prores'", movie);
  expect_refused(render(movie, {"--crf", "60"}), "--crf", movie);
  expect_refused(render(movie, {"--preset", "warp"}), "--preset: 'warp'", movie);
  expect_refused(render(movie, {"--no-frames"}), "--no-frames", movie);
  expect_refused(render(scratch("frames"), {"--crf", "20"}), "--crf", scratch("frames"));
  expect_refused(render(scratch("frames"), {"--preset", "slow"}), "--preset", scratch("frames"));
  // Under a regular file: unwritable even for root.
  std::ofstream(scratch("a-file")) << "x";
  const fs::path unwritable = scratch("a-file") / "flight.mp4";
  expect_refused(render(unwritable), unwritable.string(), unwritable);
  const fs::path not_json = scratch("not-json.json");
  std::ofstream(not_json) << "fps: 10\nkeyframes: []\n";
  expect_refused(run_relief({"render", store().string(), "--path", not_json.string(), "-o",
                             movie.string(), "--size", "320x240"},
                            kNoMesaLeakReport),
                 not_json.string(), movie);
  // FFmpeg lives in a module loaded for the first movie: one that will not load.
  expect_refused(render(movie, {}, "RELIEF_VIDEO_MODULE=" + not_json.string() + " "),
                 "video: cannot load " + not_json.string(), movie);
  expect_refused(run_relief({"render", store().string(), "--camera", "1.45,42.55,3600,20,-50,0",
                             "-o", movie.string()},
                            kNoMesaLeakReport),
                 "--path", movie);
}

TEST_F(MovieTest, FullDiskHalfWayLeavesNoMovie) {
  // A 16 KiB file size limit (relief ignores SIGXFSZ): writes fail with EFBIG
  // part way through the movie, as on a full disk.
  const fs::path movie = scratch("full-disk.mp4");
  expect_refused(render(movie, {}, "ulimit -f 16; "), movie.string(), movie);
}

TEST_F(MovieTest, KilledExportLeavesNoMovieAndTheNextExportTidiesUp) {
  // Killed while its frames render: the partial movie is a temporary file,
  // never the movie's name, and the next export of that movie removes it.
  // (The temporary exists from before the first frame to the rename; the kill
  // lands in between.)
  const fs::path movie = scratch("killed.mp4");
  const int pid = spawn_relief({"render", store().string(), "--path", path_file().string(), "-o",
                                movie.string(), "--size", "320x240"});
  ASSERT_GT(pid, 0);
  while (temporary_files(dir_->path()).empty() && ::waitpid(pid, nullptr, WNOHANG) == 0) {
    std::this_thread::sleep_for(std::chrono::milliseconds(1));
  }
  ::kill(pid, SIGKILL);
  int status = 0;
  ::waitpid(pid, &status, 0);
  ASSERT_TRUE(WIFSIGNALED(status)) << "the export finished before it was killed";
  EXPECT_FALSE(fs::exists(movie));
  EXPECT_EQ(temporary_files(dir_->path()).size(), 1u);
  const RunResult again = render(movie);
  ASSERT_EQ(again.exit_code, 0) << again.err;
  EXPECT_TRUE(temporary_files(dir_->path()).empty());
  EXPECT_EQ(probe_movie(movie).frames, 6);
}

}  // namespace
}  // namespace relief::testing
