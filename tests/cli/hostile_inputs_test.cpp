// What a hostile or careless user hands relief: files that never end (a FIFO,
// /dev/zero), files far larger than they should be, numbers that wrap, paths
// that would wait for years. Each is a one-line error naming the file or
// option, a non-zero exit, and no hang (`timeout` turns one into exit 124).
#include <signal.h>
#include <sys/stat.h>
#include <sys/wait.h>

#include <algorithm>
#include <filesystem>
#include <fstream>

#include "relief/base/file_io.h"
#include "servers.h"
#include "test_support.h"

namespace relief::testing {
namespace {
namespace fs = std::filesystem;

// Every run is bounded: a regression that blocks fails the test instead of CI.
const std::string kBounded = "timeout 60";

class HostileInputs : public SmallStoreSuite {
 protected:
  void SetUp() override {
    dir_ = std::make_unique<ScratchDir>("hostile_inputs");
    ASSERT_EQ(::mkfifo((*dir_ / "fifo").c_str(), 0600), 0);
    fs::create_symlink("/dev/zero", *dir_ / "zero");
  }
  fs::path at(const std::string& name) const { return *dir_ / name; }
  fs::path write(const std::string& name, const std::string& text) const {
    std::ofstream(at(name)) << text;
    return at(name);
  }
  // Runs relief; expects a failure whose message contains every part.
  void expect_refused(const std::vector<std::string>& args,
                      const std::vector<std::string>& parts) const {
    const RunResult r = run_relief(args, kBounded);
    EXPECT_NE(r.exit_code, 0) << r.err;
    EXPECT_NE(r.exit_code, 124) << "timed out: " << r.err;
    for (const std::string& part : parts) {
      EXPECT_NE(r.err.find(part), std::string::npos) << "'" << part << "' not in: " << r.err;
    }
    EXPECT_EQ(std::count(r.err.begin(), r.err.end(), '\n'), 1) << r.err;
  }
  std::vector<std::string> render(const std::vector<std::string>& more) const {
    std::vector<std::string> args = {"render", store().string(), "-o", at("out").string()};
    args.insert(args.end(), more.begin(), more.end());
    return args;
  }

  std::unique_ptr<ScratchDir> dir_;
};

TEST_F(HostileInputs, PathFilesThatNeverEndOrAreHugeAreRefused) {
  const std::string fifo = at("fifo").string(), zero = at("zero").string();
  expect_refused(render({"--path", fifo}), {fifo, "is a FIFO, not a regular file"});
  expect_refused(render({"--path", zero}), {zero, "is a character device"});
  const fs::path huge = at("huge.json");
  std::ofstream(huge).put('{');
  fs::resize_file(huge, uint64_t{200} << 20);  // sparse: no 200 MB written
  expect_refused(render({"--path", huge.string()}), {huge.string(), "the most this file can hold"});
  // relief view reads the same path files; its options are checked before a
  // window opens (no display needed to be refused).
  expect_refused({"view", store().string(), "--play", fifo}, {fifo, "is a FIFO"});
}

TEST_F(HostileInputs, PathsThatWouldWaitForeverAreRefused) {
  const std::string slow = write("slow.json",
                                 R"({"fps": 1e-9, "keyframes": [
    {"time": 0, "camera": [1.5, 42.5, 20000, 0, -30, 0]},
    {"time": 1, "camera": [1.6, 42.5, 20000, 0, -30, 0]}]})")
                               .string();
  expect_refused(render({"--path", slow}), {slow, "\"fps\" must be a number in [1, 1000]"});
  expect_refused(render({"--path", slow, "--fps", "0.01"}), {"--fps: must be in [1, 1000]"});
  const std::string endless = write("endless.json",
                                    R"({"fps": 30, "keyframes": [
    {"time": 0, "camera": [1.5, 42.5, 20000, 0, -30, 0]},
    {"time": 1e12, "camera": [1.6, 42.5, 20000, 0, -30, 0]}]})")
                                  .string();
  expect_refused({"view", store().string(), "--play", endless, "--exit-when-done"},
                 {endless, "more than --max-frames 100000"});
  expect_refused(render({"--path", endless}), {endless, "more than --max-frames 100000"});
  // A movie of the recorded session needs an even window: said before it starts.
  expect_refused(
      {"view", store().string(), "--size", "641x360", "--export-movie", at("m.mp4").string()},
      {"--export-movie", "641x360", "even width and height"});
}

TEST_F(HostileInputs, SizesThatWrapAtTwoToThe32AreRefused) {
  expect_refused(render({"--look-at", "1.5,42.5,1500,40000,0,-30", "--size", "4294967297x1"}),
                 {"--size: '4294967297x1' is not WxH between 1x1 and 16384x16384"});
  expect_refused(render({"--look-at", "1.5,42.5,1500,40000,0,-30", "--size", "-5x10"}), {"--size"});
  expect_refused(render({"--look-at", "1.5,42.5,1500,40000,0,-30", "--sky", "300,0,-1"}),
                 {"--sky: '300,0,-1': each of R,G,B must be in 0..255"});
  expect_refused({"build", data("srtm/N42E001.hgt.zip"), "-o", at("b").string(), "--kind",
                  "elevation", "--tile-size", "4294967808x4294967552"},
                 {"--tile-size: '4294967808x4294967552' is not WxH"});
  EXPECT_FALSE(fs::exists(at("b")));
}

// A level far past the data's own: billions of tiles whose plan alone would
// outgrow any budget are refused before anything is written.
TEST_F(HostileInputs, ABuildWhosePlanOutgrowsTheBudgetIsRefusedUpFront) {
  const std::string out = at("deep").string();
  expect_refused(
      {"build", data("srtm/N42E001.hgt.zip"), "-o", out, "--kind", "elevation", "--max-level", "24",
       "--memory", "256MiB"},
      {"level 24: the inputs cover", "whose plan alone takes about", "--memory budget 256.0 MiB"});
  EXPECT_FALSE(fs::exists(out));
}

TEST_F(HostileInputs, InputRastersThatAreFifosOrDevicesAreRefused) {
  const std::string fifo = at("fifo").string(), zero = at("zero").string();
  expect_refused({"build", fifo, "-o", at("b").string(), "--kind", "sar"}, {fifo, "is a FIFO"});
  expect_refused({"build", zero, "-o", at("b").string(), "--kind", "sar"},
                 {zero, "is a character device"});
  expect_refused({"detect", fifo, "-o", at("t.geojson").string()}, {fifo, "is a FIFO"});
  expect_refused({"process", fifo, "-o", at("p.tif").string(), "--op", "lee"}, {fifo, "is a FIFO"});
  EXPECT_FALSE(fs::exists(at("b")));
  EXPECT_FALSE(fs::exists(at("t.geojson")));
  EXPECT_FALSE(fs::exists(at("p.tif")));
}

// relief upgrade reads the manifest, the level indices and every tile itself.
TEST_F(HostileInputs, UpgradeRefusesFilesThatNeverEnd) {
  const fs::path copy = at("copy");
  fs::copy(store(), copy, fs::copy_options::recursive);
  fs::remove(copy / "manifest.json");
  ASSERT_EQ(::mkfifo((copy / "manifest.json").c_str(), 0600), 0);
  expect_refused({"upgrade", copy.string()}, {(copy / "manifest.json").string(), "is a FIFO"});
  fs::remove(copy / "manifest.json");
  fs::create_symlink("/dev/zero", copy / "manifest.json");
  expect_refused({"upgrade", copy.string()}, {"manifest.json", "is a character device"});
}

// Two valid tiles of one level: one copied over the other passes every
// checksum, but the level index says what that key's file is.
TEST_F(HostileInputs, AValidTileInTheWrongPlaceIsAnError) {
  const fs::path copy = at("copy");
  fs::copy(store(), copy, fs::copy_options::recursive);
  std::vector<fs::path> tiles;
  for (const auto& e : fs::recursive_directory_iterator(copy / "8")) {
    if (e.path().extension() == ".rtile") tiles.push_back(e.path());
  }
  std::sort(tiles.begin(), tiles.end(), [](const fs::path& a, const fs::path& b) {
    return fs::file_size(a) < fs::file_size(b);
  });
  ASSERT_GE(tiles.size(), 2u);
  ASSERT_NE(fs::file_size(tiles.front()), fs::file_size(tiles.back()));
  fs::copy_file(tiles.back(), tiles.front(), fs::copy_options::overwrite_existing);
  const std::string victim = tiles.front().string();
  expect_refused({"verify", copy.string(), "-q"},
                 {victim, "is not the tile the level index lists"});
  expect_refused({"export", copy.string(), "--level", "8", "-o", at("x.tif").string()},
                 {victim, "is not the tile the level index lists"});
  EXPECT_FALSE(fs::exists(at("x.tif")));
}

// relief split puts files into shares that a plain server then serves: a tile
// that is a symlink (to /etc/passwd), a FIFO or a sparse giant is refused.
TEST_F(HostileInputs, SplitSharesOnlyTheStoresOwnFiles) {
  const fs::path copy = at("copy");
  fs::copy(store(), copy, fs::copy_options::recursive);
  fs::path tile;
  for (const auto& e : fs::recursive_directory_iterator(copy / "8")) {
    if (e.path().extension() == ".rtile") tile = e.path();
  }
  ASSERT_FALSE(tile.empty());
  const auto split = [&](const std::string& why) {
    expect_refused({"split", copy.string(), "-o", at("shares").string(), "--shares", "2"},
                   {tile.string(), why});
    EXPECT_FALSE(fs::exists(at("shares")));
  };
  fs::remove(tile);
  fs::create_symlink("/etc/passwd", tile);
  split("is a symbolic link, not a regular file");
  fs::remove(tile);
  ASSERT_EQ(::mkfifo(tile.c_str(), 0600), 0);
  split("not a regular file");
  fs::remove(tile);
  std::ofstream(tile).put('x');
  fs::resize_file(tile, uint64_t{1} << 30);
  split("1073741824 bytes, not the");
}

// Issue 42 item 6: messages name what the user gave. A --look-at whose eye
// ends below the ground or inside the ellipsoid is --look-at's error.
TEST_F(HostileInputs, ACameraFromLookAtIsNotBlamedOnCamera) {
  expect_refused(render({"--look-at", "1.5,42.5,0,100,0,-30", "--size", "64x48"}),
                 {"--look-at: the camera at", "is below the ground"});
  expect_refused(render({"--look-at", "1.5,42.5,-12000,5000,0,-10", "--size", "64x48"}),
                 {"--look-at: the camera's height", "inside the ellipsoid"});
  const RunResult r =
      run_relief(render({"--look-at", "1.5,42.5,0,100,0,-30", "--size", "64x48"}), kBounded);
  EXPECT_EQ(r.err.find("--camera"), std::string::npos) << r.err;
}

// The disk cache of a remote store: its budget holds for every file (0
// keeps nothing, not the last tile), and a directory it cannot write in
// (/proc/self) is a one-line error naming it, not an internal error.
TEST_F(HostileInputs, TheDiskCacheKeepsItsBudgetAndRefusesUnwritableDirectories) {
  const int port = free_port();
  const int pid = spawn_relief({"serve", store().string(), "--port", std::to_string(port)});
  wait_for(port);
  const std::string url = "http://127.0.0.1:" + std::to_string(port);
  auto remote = [&](const std::string& cache, const std::string& size) {
    return std::vector<std::string>{"render",  url,     "--look-at",    "1.5,42.5,0,20000,0,-30",
                                    "--size",  "64x48", "-o",           at("remote.png").string(),
                                    "--cache", cache,   "--cache-size", size};
  };
  const RunResult zero =
      run_relief(remote(at("cache0").string(), "0"), kNoMesaLeakReport + kBounded);
  EXPECT_EQ(zero.exit_code, 0) << zero.err;
  EXPECT_EQ(regular_files_under(at("cache0")), 0u);
  const RunResult small =
      run_relief(remote(at("cache1").string(), "100K"), kNoMesaLeakReport + kBounded);
  EXPECT_EQ(small.exit_code, 0) << small.err;
  uint64_t bytes = 0;
  for (const auto& e : fs::recursive_directory_iterator(at("cache1"))) {
    if (e.is_regular_file()) bytes += e.file_size();
  }
  EXPECT_LE(bytes, uint64_t{100} << 10);
  expect_refused(remote("/proc/self", "1M"),
                 {"/proc/self: not a directory the disk cache can write in"});
  ::kill(pid, SIGTERM);
  ::waitpid(pid, nullptr, 0);
}

}  // namespace
}  // namespace relief::testing
