// Inputs in other formats GDAL reads (DTED, COG, VRT) give the same store as
// the original .hgt; the build is deterministic across memory budgets and
// thread counts, and stays within its memory budget.
#include <gtest/gtest.h>

#include <cstdio>
#include <map>

#include "relief/base/file_io.h"
#include "test_support.h"

namespace relief::testing {
namespace {
namespace fs = std::filesystem;

const std::string kHgt = data("srtm/N42E001.hgt.zip");

std::map<std::string, std::vector<std::byte>> tile_files(const fs::path& root) {
  std::map<std::string, std::vector<std::byte>> files;
  for (const auto& e : fs::recursive_directory_iterator(root)) {
    if (e.path().extension() == ".rtile" || e.path().extension() == ".rli") {
      files[fs::relative(e.path(), root).generic_string()] = *read_file(e.path(), kNoSizeLimit);
    }
  }
  return files;
}

void build_ok(const std::vector<std::string>& args) {
  auto r = run_relief(args);
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_TRUE(r.err.empty()) << "no progress output when stderr is not a terminal: " << r.err;
}

TEST(Formats, DtedCogAndVrtInputsGiveTheSameTiles) {
  ScratchDir dir("formats");
  const std::string hgt_store = (dir / "hgt").string();
  build_ok({"build", kHgt, "-o", hgt_store, "--kind", "elevation", "-q"});
  const auto expected = tile_files(hgt_store);

  const std::string src = "/vsizip/" + kHgt + "/N42E001.hgt";
  const std::string dted = (dir / "n42.dt1").string(), cog = (dir / "n42.tif").string(),
                    vrt = (dir / "n42.vrt").string();
  // SRTM3 tiles have exactly the shape of DTED level 1 below 50 degrees.
  ASSERT_EQ(std::system(("gdal_translate -q -of DTED " + src + " " + dted).c_str()), 0);
  ASSERT_EQ(
      std::system(("gdal_translate -q -of COG -co COMPRESS=DEFLATE " + src + " " + cog).c_str()),
      0);
  ASSERT_EQ(std::system(("gdalbuildvrt -q " + vrt + " " + src).c_str()), 0);
  for (const auto& input : {dted, cog, vrt}) {
    SCOPED_TRACE(input);
    const std::string store = (dir / fs::path(input).extension().string().substr(1)).string();
    build_ok({"build", input, "-o", store, "--kind", "elevation", "-q"});
    const auto got = tile_files(store);
    ASSERT_EQ(got.size(), expected.size());
    for (const auto& [name, bytes] : expected) EXPECT_TRUE(got.at(name) == bytes) << name;
  }
}

TEST(Formats, BuildIsDeterministicAcrossBudgetsAndThreads) {
  ScratchDir dir("budgets");
  std::map<std::string, std::vector<std::byte>> first;
  for (const char* memory : {"128MiB", "1GiB"}) {
    for (const char* threads : {"1", "2"}) {
      SCOPED_TRACE(std::string(memory) + " x " + threads + " threads");
      const std::string store = (dir / (std::string(memory) + "_" + threads)).string();
      build_ok({"build", data("srtm/N41E001.hgt.zip"), kHgt, "-o", store, "--kind", "elevation",
                "--memory", memory, "--threads", threads, "-q"});
      const auto files = tile_files(store);
      if (first.empty()) first = files;
      ASSERT_EQ(files.size(), first.size());
      for (const auto& [name, bytes] : first) EXPECT_TRUE(files.at(name) == bytes) << name;
    }
  }
}

TEST(Formats, SmallBudgetBuildStaysWithinIt) {
  ScratchDir dir("small_budget");
  const std::string store = (dir / "s").string();
  auto r = run_relief({"build", data("srtm/N41E001.hgt.zip"), kHgt, "-o", store, "--kind",
                       "elevation", "--memory", "128MiB", "-q"},
                      "exec /usr/bin/time -f '%M' -o " + (dir / "rss").string());
  ASSERT_EQ(r.exit_code, 0) << r.err;
  const std::string rss = *read_text_file(dir / "rss", kNoSizeLimit);
  const double peak_mib = std::stod(rss) / 1024.0;
  std::printf("peak RSS of a 128 MiB-budget build: %.1f MiB\n", peak_mib);
  EXPECT_LT(peak_mib, 128.0) << "the budget covers the whole process";
}

// The peak resident memory of `relief ARGS`, in MiB.
double peak_mib(const std::vector<std::string>& args, const fs::path& rss_file) {
  auto r = run_relief(args, "exec /usr/bin/time -f '%M' -o " + rss_file.string());
  EXPECT_EQ(r.exit_code, 0) << r.err;
  return std::stod(*read_text_file(rss_file, kNoSizeLimit)) / 1024.0;
}

// Two tiles built a level past their data under the smallest budget two
// workers may have: 248 tiles' cores, the allocator's freed pages and the
// geometric errors' cache took 120 MiB of 112 before the build held its
// resident memory under a mark (ingest's MemoryGovernor). Their export at
// that level (about 2 900 x 5 800 samples, 68 MB) under the least export budget:
// GDAL's cache held every block of the output before --memory capped it.
TEST(Formats, ABuildPastItsDataAndItsExportStayWithinTheSmallestBudgets) {
  ScratchDir dir("smallest_budget");
  const std::string store = (dir / "s").string();
  const double build = peak_mib(
      {"build", data("srtm/N41E001.hgt.zip"), data("srtm/N42E001.hgt.zip"), "-o", store, "--kind",
       "elevation", "--max-level", "11", "--threads", "2", "--memory", "112MiB", "-q"},
      dir / "build_rss");
  std::printf("peak RSS of a 112 MiB-budget build of 2 tiles at level 11: %.1f MiB\n", build);
  EXPECT_LT(build, 112.0) << "the budget covers the whole process";
  const fs::path tif = dir / "level11.tif";
  const double exported =
      peak_mib({"export", store, "--level", "11", "--memory", "96MiB", "-o", tif.string(), "-q"},
               dir / "export_rss");
  std::printf("peak RSS of a 96 MiB-budget export of level 11: %.1f MiB\n", exported);
  EXPECT_LT(exported, 96.0) << "the budget covers the whole process";
  EXPECT_GT(fs::file_size(tif), uint64_t{10} << 20);
}

}  // namespace
}  // namespace relief::testing
