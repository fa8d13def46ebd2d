// Outputs that would destroy inputs: every command that writes refuses an
// output that is one of its inputs (by name, symlink or hard link), lies inside
// an input store, contains an input, or is a device node or FIFO. Each refusal
// is one line naming the argument, a non-zero exit, and the inputs unchanged.
#include <gtest/gtest.h>
#include <sys/stat.h>

#include <map>

#include "relief/base/file_io.h"
#include "test_support.h"

namespace relief::testing {
namespace {
namespace fs = std::filesystem;

// Every file below `dir` with its bytes: a store is unchanged when this is.
std::map<std::string, std::string> snapshot(const fs::path& dir) {
  std::map<std::string, std::string> files;
  for (const auto& e : fs::recursive_directory_iterator(dir)) {
    if (e.is_regular_file()) {
      files[fs::relative(e.path(), dir).string()] =
          read_text_file(e.path(), kNoSizeLimit).value_or("?");
    }
  }
  return files;
}

class OutputSafety : public ::testing::Test {
 protected:
  static void SetUpTestSuite() {
    dir_ = new ScratchDir("output_safety");
    store_ = (dir_->path() / "pyr").string();
    ASSERT_EQ(run_relief({"build", data("srtm/N42E001.hgt.zip"), "--kind", "elevation", "-o",
                          store_, "--min-level", "8", "-q"})
                  .exit_code,
              0);
    raster_ = (dir_->path() / "in.tif").string();
    ASSERT_EQ(std::system(("gdal_translate -q -srcwin 600 700 64 64 " +
                           data("sar/umbra_mount_yasur.tif") + " " + raster_)
                              .c_str()),
              0);
  }
  static void TearDownTestSuite() {
    delete dir_;
    dir_ = nullptr;
  }
  void SetUp() override {
    store_before_ = snapshot(store_);
    raster_before_ = read_text_file(raster_, kNoSizeLimit).value_or("");
  }
  void TearDown() override {
    EXPECT_EQ(snapshot(store_), store_before_) << "the input store changed";
    EXPECT_EQ(read_text_file(raster_, kNoSizeLimit).value_or(""), raster_before_)
        << "the input raster changed";
    EXPECT_TRUE(temporary_files(dir_->path()).empty());
  }
  // The path of one tile of the store.
  static std::string a_tile() {
    for (const auto& e : fs::recursive_directory_iterator(store_)) {
      if (e.path().extension() == ".rtile") return e.path().string();
    }
    return "";
  }
  static fs::path scratch(const std::string& name) { return dir_->path() / name; }

  static inline ScratchDir* dir_ = nullptr;
  static inline std::string store_, raster_;
  std::map<std::string, std::string> store_before_;
  std::string raster_before_;
};

const std::string kLookAt = "1.5,42.5,1000,20000,0,-30";

TEST_F(OutputSafety, ExportIntoItsStoreIsRefused) {
  const std::string manifest = store_ + "/manifest.json";
  EXPECT_TRUE(is_one_line_error(
      run_relief({"export", store_, "--level", "9", "-o", manifest, "-q"}), "-o: " + manifest));
  const std::string tile = a_tile();
  EXPECT_TRUE(is_one_line_error(run_relief({"export", store_, "--level", "9", "-o", tile, "-q"}),
                                "inside the input store"));
  // Spelled through "..", or as the store itself.
  const std::string dotted = store_ + "/../pyr/x.tif";
  EXPECT_TRUE(is_one_line_error(run_relief({"export", store_, "--level", "9", "-o", dotted, "-q"}),
                                "inside the input store"));
  EXPECT_TRUE(is_one_line_error(run_relief({"export", store_, "--level", "9", "-o", store_, "-q"}),
                                "is also an input"));
  EXPECT_EQ(run_relief({"verify", store_, "-q"}).exit_code, 0);
}

TEST_F(OutputSafety, RenderIntoItsStoreIsRefused) {
  const std::string manifest = store_ + "/manifest.json";
  EXPECT_TRUE(is_one_line_error(
      run_relief({"render", store_, "--look-at", kLookAt, "--size", "32x24", "-o", manifest},
                 kNoMesaLeakReport),
      "-o: " + manifest));
  EXPECT_TRUE(is_one_line_error(
      run_relief({"render", store_, "--look-at", kLookAt, "--size", "32x24", "-o",
                  scratch("still.png").string(), "--stats", store_ + "/stats.json"},
                 kNoMesaLeakReport),
      "--stats"));
  const std::string path = data("paths/pyrenees-flight.json");
  EXPECT_TRUE(is_one_line_error(
      run_relief({"render", store_, "--path", path, "--size", "32x24", "-o", store_ + "/frames"},
                 kNoMesaLeakReport),
      "-o"));
  EXPECT_TRUE(is_one_line_error(
      run_relief({"render", store_, "--path", path, "--size", "32x24", "--no-frames", "-o",
                  scratch("frames").string(), "--events", store_ + "/events.jsonl"},
                 kNoMesaLeakReport),
      "--events"));
  EXPECT_FALSE(fs::exists(scratch("still.png")));
}

TEST_F(OutputSafety, ProcessOverItsInputIsRefused) {
  EXPECT_TRUE(
      is_one_line_error(run_relief({"process", raster_, "-o", raster_, "--op", "lee", "-q"}),
                        "-o: " + raster_ + " is also an input"));
  const std::string link = scratch("link.tif").string();
  fs::create_symlink(raster_, link);
  EXPECT_TRUE(is_one_line_error(run_relief({"process", raster_, "-o", link, "--op", "lee", "-q"}),
                                "is the input"));
  EXPECT_TRUE(fs::is_symlink(link));
  const std::string hard = scratch("hard.tif").string();
  fs::create_hard_link(raster_, hard);
  EXPECT_TRUE(is_one_line_error(run_relief({"process", raster_, "-o", hard, "--op", "lee", "-q"}),
                                "is the input"));
  fs::remove(link);
  fs::remove(hard);
}

TEST_F(OutputSafety, DetectOverItsInputIsRefused) {
  const std::string geojson = scratch("targets.geojson").string();
  EXPECT_TRUE(is_one_line_error(run_relief({"detect", raster_, "-o", raster_, "-q"}), "-o"));
  EXPECT_TRUE(is_one_line_error(
      run_relief({"detect", raster_, "-o", geojson, "--plot", raster_, "-q"}), "--plot"));
  EXPECT_TRUE(is_one_line_error(
      run_relief({"detect", raster_, "-o", geojson, "--analysis", raster_, "-q"}), "--analysis"));
  // Two outputs on one file: the second would silently replace the first.
  EXPECT_TRUE(
      is_one_line_error(run_relief({"detect", raster_, "-o", geojson, "--analysis", geojson, "-q"}),
                        "--analysis: " + geojson + " is also the output of -o"));
  EXPECT_FALSE(fs::exists(geojson));
}

TEST_F(OutputSafety, ProcessStoreInsideItsInputStoreIsRefused) {
  const std::string inside = store_ + "/processed";
  EXPECT_TRUE(is_one_line_error(run_relief({"process", store_, "-o", inside, "--op", "mean", "-q"}),
                                "-o: " + inside + " lies inside the input store"));
  EXPECT_FALSE(fs::exists(inside));
  EXPECT_EQ(run_relief({"verify", store_, "-q"}).exit_code, 0);
}

TEST_F(OutputSafety, StoreOutputContainingAnInputIsRefused) {
  const std::string parent = dir_->path().string();
  EXPECT_TRUE(is_one_line_error(run_relief({"fuse", store_, store_, "-o", parent, "-q"}),
                                "contains the input"));
  EXPECT_TRUE(is_one_line_error(run_relief({"process", store_, "-o", parent, "--op", "mean", "-q"}),
                                "contains the input"));
}

// A FIFO would block the writer or be replaced; a device node (as root) would
// be replaced by a regular file. The FIFO comes first: were it not refused, the
// test stops (ASSERT) before it could touch the machine's /dev/null.
TEST_F(OutputSafety, DeviceAndFifoOutputsAreRefused) {
  const fs::path fifo = scratch("fifo");
  ASSERT_EQ(::mkfifo(fifo.c_str(), 0644), 0);
  ASSERT_TRUE(is_one_line_error(
      run_relief({"export", store_, "--level", "9", "-o", fifo.string(), "-q"}), "-o"));
  ASSERT_TRUE(fs::is_fifo(fifo));
  ASSERT_TRUE(
      is_one_line_error(run_relief({"detect", raster_, "-o", fifo.string(), "-q"}), "FIFO"));
  ASSERT_TRUE(fs::is_fifo(fifo));
  EXPECT_TRUE(
      is_one_line_error(run_relief({"export", store_, "--level", "9", "-o", "/dev/null", "-q"}),
                        "-o: /dev/null: is a character device"));
  EXPECT_TRUE(fs::is_character_file("/dev/null"));
  fs::remove(fifo);
}

}  // namespace
}  // namespace relief::testing
