// The command line on real data: help, bad arguments, bad inputs, unwritable
// outputs, a full disk, corrupt tiles. Every failure is one line naming the
// argument or file, a non-zero exit, and nothing half-written.
#include <gtest/gtest.h>

#include <fstream>

#include <nlohmann/json.hpp>

#include "relief/base/file_io.h"
#include "test_support.h"

namespace relief::testing {
namespace {
namespace fs = std::filesystem;

const std::string kPyrenees = data("srtm/N42E001.hgt.zip");

int line_count(const std::string& s) {
  return static_cast<int>(std::count(s.begin(), s.end(), '\n'));
}

// A failed run: non-zero exit, exactly one line on stderr, mentioning `needle`.
void expect_one_line_error(const RunResult& r, const std::string& needle) {
  EXPECT_NE(r.exit_code, 0);
  EXPECT_EQ(line_count(r.err), 1) << r.err;
  EXPECT_NE(r.err.find(needle), std::string::npos) << "stderr: " << r.err;
  EXPECT_EQ(r.err.rfind("relief: ", 0), 0u) << r.err;
}

TEST(Cli, HelpListsCommands) {
  auto r = run_relief({"--help"});
  EXPECT_EQ(r.exit_code, 0);
  for (const char* cmd : {"build", "info", "verify", "export"}) {
    EXPECT_NE(r.out.find(cmd), std::string::npos) << cmd;
    auto sub = run_relief({cmd, "--help"});
    EXPECT_EQ(sub.exit_code, 0) << cmd;
    EXPECT_NE(sub.out.find("usage: relief"), std::string::npos) << cmd;
  }
  EXPECT_EQ(run_relief({}).exit_code, 2);
  expect_one_line_error(run_relief({"frobnicate"}), "frobnicate");
}

// The executable runs on the allocator its build chose, page size left to
// the system (docs/building.md, "Allocator"); MALLOC_CONF is not set by the test.
TEST(Cli, VersionNamesTheAllocator) {
  const auto r = run_relief({"--version"});
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_EQ(r.out.rfind("relief ", 0), 0u) << r.out;
  if (RELIEF_EXPECT_JEMALLOC) {
    EXPECT_NE(r.out.find("allocator: jemalloc "), std::string::npos) << r.out;
    EXPECT_NE(r.out.find("(transparent huge pages: default)"), std::string::npos) << r.out;
  } else {
    EXPECT_NE(r.out.find("allocator: system malloc"), std::string::npos) << r.out;
  }
}

TEST(Cli, BadArgumentsNameTheArgument) {
  ScratchDir dir("cli_args");
  const std::string out = (dir / "s").string();
  expect_one_line_error(
      run_relief({"build", kPyrenees, "-o", out, "--kind", "elevation", "--bogus"}), "--bogus");
  expect_one_line_error(run_relief({"build", kPyrenees, "-o", out, "--kind", "lava"}), "lava");
  expect_one_line_error(
      run_relief({"build", kPyrenees, "-o", out, "--kind", "elevation", "--max-level", "abc"}),
      "--max-level");
  expect_one_line_error(
      run_relief({"build", kPyrenees, "-o", out, "--kind", "elevation", "--max-level", "99"}),
      "--max-level");
  expect_one_line_error(
      run_relief({"build", kPyrenees, "-o", out, "--kind", "elevation", "--memory", "1XB"}),
      "--memory");
  expect_one_line_error(
      run_relief({"build", kPyrenees, "-o", out, "--kind", "elevation", "--memory", "1MiB"}),
      "--memory");
  expect_one_line_error(
      run_relief({"build", kPyrenees, "-o", out, "--kind", "elevation", "--codec", "png"}),
      "--codec");
  expect_one_line_error(
      run_relief({"build", kPyrenees, "-o", out, "--kind", "elevation", "--max-error", "-1"}),
      "--max-error");
  expect_one_line_error(
      run_relief({"build", kPyrenees, "-o", out, "--kind", "elevation", "--tile-size", "300x200"}),
      "--tile-size");
  expect_one_line_error(
      run_relief({"build", kPyrenees, "-o", out, "--kind", "elevation", "--border", "-2"}),
      "--border");
  expect_one_line_error(
      run_relief({"build", kPyrenees, "-o", out, "--kind", "sar", "--fill-voids"}), "--fill-voids");
  expect_one_line_error(run_relief({"build", kPyrenees, "-o", out}), "--kind");
  expect_one_line_error(run_relief({"build", kPyrenees, "--kind", "elevation"}), "-o");
  expect_one_line_error(run_relief({"build", "-o", out, "--kind", "elevation"}), "no input");
  expect_one_line_error(run_relief({"build", kPyrenees, "-o"}), "-o");
  expect_one_line_error(run_relief({"export", out, "--level", "1"}), "-o");
  expect_one_line_error(run_relief({"export", out, "-o", "x.tif"}), "--level");
  expect_one_line_error(run_relief({"info"}), "STORE");
  EXPECT_FALSE(fs::exists(out)) << "nothing may be written on bad arguments";
}

TEST(Cli, BadInputsNameTheFile) {
  ScratchDir dir("cli_inputs");
  const std::string out = (dir / "s").string();
  auto build = [&](std::vector<std::string> inputs, const std::string& kind,
                   std::vector<std::string> extra = {}) {
    std::vector<std::string> args = {"build"};
    args.insert(args.end(), inputs.begin(), inputs.end());
    args.insert(args.end(), {"-o", out, "--kind", kind});
    args.insert(args.end(), extra.begin(), extra.end());
    return run_relief(args);
  };
  const std::string missing = (dir / "missing.tif").string();
  expect_one_line_error(build({missing}, "elevation"), missing);

  const std::string text = (dir / "notes.txt").string();
  std::ofstream(text) << "this is not a raster\n";
  expect_one_line_error(build({text}, "elevation"), text);

  // A PNG without any georeferencing.
  const std::string png = (dir / "plain.png").string();
  ASSERT_EQ(std::system(("gdal_translate -q -of PNG -outsize 16 16 " +
                         data("imagery/RGB.byte.tif") + " " + png + " 2>/dev/null")
                            .c_str()),
            0);
  fs::remove(png + ".aux.xml");
  expect_one_line_error(build({png}, "imagery"), "no georeferencing");

  // A world file in metres but no CRS: refused with a hint, accepted with
  // --src-crs. (One whose extent can only be degrees is taken as WGS84.)
  const std::string jpg = (dir / "utm.png").string();
  fs::copy_file(png, jpg);
  std::ofstream(dir / "utm.pgw") << "30\n0\n0\n-30\n500015\n4649985\n";
  expect_one_line_error(build({jpg}, "imagery"), "--src-crs");
  auto ok = build({jpg}, "imagery", {"--src-crs", "EPSG:32631", "-q"});
  EXPECT_EQ(ok.exit_code, 0) << ok.err;
  fs::remove_all(out);
  expect_one_line_error(build({jpg}, "imagery", {"--src-crs", "EPSG:999999"}), "--src-crs");
  const std::string globe = (dir / "globe.png").string();
  fs::copy_file(png, globe);
  std::ofstream(dir / "globe.pgw") << "22.5\n0\n0\n-11.25\n-168.75\n84.375\n";
  auto assumed = build({globe}, "imagery", {"-q"});
  EXPECT_EQ(assumed.exit_code, 0) << assumed.err;
  fs::remove_all(out);

  // Complex samples (an SLC-like product).
  const std::string complex = (dir / "slc.tif").string();
  ASSERT_EQ(std::system(("gdal_translate -q -ot CInt16 -outsize 32 32 " + kPyrenees + " " +
                         complex + " 2>/dev/null")
                            .c_str()),
            0);
  expect_one_line_error(build({complex}, "sar"), "unsupported data type CInt16");

  // Inputs that conflict with the kind or with each other.
  expect_one_line_error(build({data("imagery/RGB.byte.tif")}, "elevation"), "3 bands");
  expect_one_line_error(build({kPyrenees}, "imagery"), "unsupported data type Int16");
  const std::string grey = (dir / "grey.tif").string();
  ASSERT_EQ(
      std::system(("gdal_translate -q -b 1 " + data("imagery/RGB.byte.tif") + " " + grey).c_str()),
      0);
  expect_one_line_error(build({grey, data("imagery/RGB.byte.tif")}, "imagery"), "colour bands");
  EXPECT_FALSE(fs::exists(out));
}

TEST(Cli, UnwritableAndExistingOutputs) {
  ScratchDir dir("cli_outputs");
  expect_one_line_error(
      run_relief({"build", kPyrenees, "-o", "/proc/relief/store", "--kind", "elevation"}),
      "/proc/relief/store");
  const std::string file = (dir / "afile").string();
  std::ofstream(file) << "x";
  expect_one_line_error(run_relief({"build", kPyrenees, "-o", file, "--kind", "elevation"}),
                        "not a directory");
  fs::create_directories(dir / "other");
  std::ofstream(dir / "other" / "precious.txt") << "keep me";
  expect_one_line_error(
      run_relief({"build", kPyrenees, "-o", (dir / "other").string(), "--kind", "elevation"}),
      "not a relief store");
  EXPECT_TRUE(fs::exists(dir / "other" / "precious.txt"));

  const std::string store = (dir / "store").string();
  const std::vector<std::string> args = {"build",     kPyrenees,     "-o", store, "--kind",
                                         "elevation", "--min-level", "8",  "-q"};
  ASSERT_EQ(run_relief(args).exit_code, 0);
  expect_one_line_error(run_relief(args), "--overwrite");
  auto again = args;
  again.push_back("--overwrite");
  EXPECT_EQ(run_relief(again).exit_code, 0);
  std::vector<std::string> exported = {"export", store, "--level", "9", "-o", "/proc/relief/x.tif"};
  expect_one_line_error(run_relief(exported), "/proc/relief/x.tif");
  expect_one_line_error(
      run_relief({"export", store, "--level", "3", "-o", (dir / "x.tif").string()}), "--level");
  expect_one_line_error(run_relief({"export", store, "--level", "9", "--bbox", "1,2,3", "-o",
                                    (dir / "x.tif").string()}),
                        "--bbox");
  expect_one_line_error(run_relief({"export", store, "--level", "9", "--bbox", "5,42,1,43", "-o",
                                    (dir / "x.tif").string()}),
                        "--bbox");
  EXPECT_FALSE(fs::exists(dir / "x.tif"));
  expect_one_line_error(run_relief({"info", (dir / "nothing").string()}), "nothing");
}

// A file-size limit makes writes fail with EFBIG, as a full disk makes them fail
// with ENOSPC: the build stops with an error, leaves no partial file, and a
// later run resumes to a complete, valid store.
TEST(Cli, FullDiskFailsCleanlyAndResumes) {
  ScratchDir dir("cli_full");
  const std::string store = (dir / "store").string();
  const std::vector<std::string> args = {"build",  kPyrenees,   "-o", store,
                                         "--kind", "elevation", "-q"};
  auto r = run_relief(args, "ulimit -f 150;");
  expect_one_line_error(r, "File too large");
  EXPECT_TRUE(temporary_files(store).empty());
  EXPECT_FALSE(fs::exists(fs::path(store) / "manifest.json"));
  auto resumed = run_relief(args);
  ASSERT_EQ(resumed.exit_code, 0) << resumed.err;
  EXPECT_NE(resumed.out.find("resumed"), std::string::npos);
  auto verify = run_relief({"verify", store, "-q"});
  EXPECT_EQ(verify.exit_code, 0) << verify.err;
  EXPECT_TRUE(temporary_files(store).empty());
}

TEST(Cli, InfoReportsLevelsAndCompression) {
  ScratchDir dir("cli_info");
  const std::string store = (dir / "store").string();
  ASSERT_EQ(run_relief({"build", kPyrenees, "-o", store, "--kind", "elevation", "-q"}).exit_code,
            0);
  auto text = run_relief({"info", store});
  EXPECT_EQ(text.exit_code, 0);
  EXPECT_NE(text.out.find("compression"), std::string::npos);
  EXPECT_NE(text.out.find("EPSG:4326"), std::string::npos);
  auto js = run_relief({"info", store, "--json"});
  ASSERT_EQ(js.exit_code, 0);
  const auto j = nlohmann::json::parse(js.out);
  EXPECT_EQ(j["manifest"]["kind"], "elevation");
  EXPECT_EQ(j["manifest"]["levels"]["max"], 10);
  EXPECT_EQ(j["levels"].size(), 11u);
  uint64_t tiles = 0;
  for (const auto& l : j["levels"]) tiles += l["tiles"].get<uint64_t>();
  EXPECT_EQ(j["total"]["tiles"].get<uint64_t>(), tiles);
  EXPECT_GT(j["total"]["compression_ratio"].get<double>(), 1.5);
}

class CorruptStore : public ::testing::Test {
 protected:
  void SetUp() override {
    ASSERT_EQ(run_relief({"build", kPyrenees, "-o", store_, "--kind", "elevation", "--min-level",
                          "9", "-q"})
                  .exit_code,
              0);
    for (const auto& e : fs::recursive_directory_iterator(store_)) {
      if (e.path().extension() == ".rtile") tiles_.push_back(e.path());
    }
    std::sort(tiles_.begin(), tiles_.end());
    ASSERT_GT(tiles_.size(), 10u);
  }
  ScratchDir dir_{"cli_corrupt"};
  std::string store_ = (dir_ / "store").string();
  std::vector<fs::path> tiles_;
};

TEST_F(CorruptStore, VerifyNamesEachBadTile) {
  EXPECT_EQ(run_relief({"verify", store_, "-q"}).exit_code, 0);
  // Flip a payload byte in one tile, truncate another, delete a third, leave a stray temp file.
  {
    std::fstream f(tiles_[0], std::ios::in | std::ios::out | std::ios::binary);
    f.seekp(200);
    char c = 0;
    f.read(&c, 1);
    f.seekp(200);
    c = static_cast<char>(c ^ 0x55);
    f.write(&c, 1);
  }
  fs::resize_file(tiles_[1], fs::file_size(tiles_[1]) / 2);
  fs::remove(tiles_[2]);
  std::ofstream(tiles_[3].string() + ".tmp.123.0") << "partial";
  auto r = run_relief({"verify", store_, "-q"});
  EXPECT_EQ(r.exit_code, 1);
  EXPECT_EQ(line_count(r.err), 4) << r.err;
  EXPECT_NE(r.err.find(tiles_[0].string() + ": tile payload checksum mismatch"), std::string::npos)
      << r.err;
  EXPECT_NE(r.err.find(tiles_[1].string() + ": truncated tile"), std::string::npos) << r.err;
  EXPECT_NE(r.err.find(tiles_[2].string() + ": tile"), std::string::npos) << r.err;
  EXPECT_NE(r.err.find("missing"), std::string::npos) << r.err;
  EXPECT_NE(r.err.find("leftover temporary file"), std::string::npos) << r.err;
}

TEST_F(CorruptStore, ExportOfACorruptTileIsAnErrorNotACrash) {
  // Garbage after a valid header: the checksum catches it.
  {
    std::fstream f(tiles_.back(), std::ios::in | std::ios::out | std::ios::binary);
    f.seekp(100);
    const std::string junk(64, '\x7f');
    f.write(junk.data(), static_cast<std::streamsize>(junk.size()));
  }
  const std::string out = (dir_ / "out.tif").string();
  const std::string level = tiles_.back().lexically_relative(store_).begin()->string();
  auto r = run_relief({"export", store_, "--level", level, "-o", out, "-q"});
  expect_one_line_error(r, tiles_.back().string());
  EXPECT_FALSE(fs::exists(out));
  EXPECT_TRUE(temporary_files(dir_.path()).size() == 0 || !fs::exists(out));
}

TEST_F(CorruptStore, DamagedManifestOrIndexIsReported) {
  fs::resize_file(fs::path(store_) / "10" / "index.rli", 10);
  auto r = run_relief({"info", store_});
  expect_one_line_error(r, "index.rli");
  std::ofstream(fs::path(store_) / "manifest.json") << "{ not json";
  expect_one_line_error(run_relief({"verify", store_}), "manifest.json");
}

}  // namespace
}  // namespace relief::testing
