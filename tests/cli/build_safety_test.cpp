// `relief build` and `relief fuse` never destroy what is not theirs and never
// write a store that cannot be read back: --overwrite replaces only a relief
// store, an input is never inside the output, infinite samples and weights do
// not reach the manifest, absurd memory budgets are refused, and temporaries
// of killed runs are cleaned.
#include <gdal.h>
#include <gtest/gtest.h>
#include <ogr_srs_api.h>
#include <sys/wait.h>
#include <unistd.h>

#include <cmath>
#include <fstream>

#include <fmt/format.h>
#include <nlohmann/json.hpp>

#include "relief/base/file_io.h"
#include "relief/tiles/store.h"
#include "test_support.h"

namespace relief::testing {
namespace {
namespace fs = std::filesystem;

const std::string kEast = data("srtm/N55W003.hgt.zip");
const std::string kWest = data("srtm/N55W004.hgt.zip");

std::vector<std::string> build(const std::string& in, const fs::path& out) {
  return {"build", in, "-o", out.string(), "--kind", "elevation", "--max-level", "5", "-q"};
}

void expect_one_line_error(const RunResult& r, const std::string& needle) {
  EXPECT_NE(r.exit_code, 0);
  EXPECT_EQ(std::count(r.err.begin(), r.err.end(), '\n'), 1) << r.err;
  EXPECT_NE(r.err.find(needle), std::string::npos) << "stderr: " << r.err;
}

std::string contents(const fs::path& p) {
  auto text = read_text_file(p, kNoSizeLimit);
  return text ? *text : "<unreadable>";
}

// A 64 x 64 float32 GeoTIFF in EPSG:4326 over 10..11 E, 45..46 N.
void write_float_raster(const fs::path& path, const std::vector<float>& values) {
  GDALAllRegister();
  GDALDatasetH ds =
      GDALCreate(GDALGetDriverByName("GTiff"), path.c_str(), 64, 64, 1, GDT_Float32, nullptr);
  ASSERT_NE(ds, nullptr);
  double gt[6] = {10, 1.0 / 64, 0, 46, 0, -1.0 / 64};
  GDALSetGeoTransform(ds, gt);
  OGRSpatialReferenceH srs = OSRNewSpatialReference(nullptr);
  OSRImportFromEPSG(srs, 4326);
  GDALSetSpatialRef(ds, srs);
  OSRDestroySpatialReference(srs);
  ASSERT_EQ(GDALRasterIO(GDALGetRasterBand(ds, 1), GF_Write, 0, 0, 64, 64,
                         const_cast<float*>(values.data()), 64, 64, GDT_Float32, 0, 0),
            CE_None);
  GDALClose(ds);
}

std::vector<float> ramp() {
  std::vector<float> v(64 * 64);
  for (size_t i = 0; i < v.size(); ++i) v[i] = 100.0f + static_cast<float>(i % 64 + i / 64);
  return v;
}

TEST(BuildOverwrite, RefusesADirectoryHoldingOtherFiles) {
  ScratchDir dir("overwrite_foreign");
  const fs::path p = dir / "p";
  fs::create_directories(p);
  std::ofstream(p / "manifest.json") << "{}\n";
  std::ofstream(p / "notes.txt") << "x\n";
  auto args = build(kEast, p);
  args.push_back("--overwrite");
  expect_one_line_error(run_relief(args), "not provably a relief store");
  EXPECT_EQ(contents(p / "notes.txt"), "x\n");
  EXPECT_EQ(contents(p / "manifest.json"), "{}\n");

  // A real store with a file of the user's in it is not replaced either.
  const fs::path s = dir / "s";
  ASSERT_EQ(run_relief(build(kEast, s)).exit_code, 0);
  std::ofstream(s / "notes.txt") << "mine\n";
  args = build(kWest, s);
  args.push_back("--overwrite");
  expect_one_line_error(run_relief(args), "notes.txt");
  EXPECT_EQ(contents(s / "notes.txt"), "mine\n");
  EXPECT_TRUE(fs::exists(s / "manifest.json"));
  fs::create_directories(s / "photos");  // an empty directory of the user's too
  fs::remove(s / "notes.txt");
  expect_one_line_error(run_relief(args), "photos");
  fs::remove(s / "photos");
  // Store files only: replaced.
  EXPECT_EQ(run_relief(args).exit_code, 0);
  EXPECT_EQ(run_relief({"verify", s.string(), "-q"}).exit_code, 0);
}

TEST(BuildOverwrite, NeverTouchesAnInput) {
  ScratchDir dir("overwrite_input");
  const fs::path st = dir / "st";
  fs::create_directories(st);
  const fs::path input = st / "N55W003.hgt.zip";
  fs::copy_file(kEast, input);
  const auto before = read_file(input, kNoSizeLimit);
  ASSERT_TRUE(before);
  for (const std::string& in : {input.string(), "/vsizip/" + input.string() + "/N55W003.hgt"}) {
    SCOPED_TRACE(in);
    auto args = build(in, st);
    args.push_back("--overwrite");
    expect_one_line_error(run_relief(args), "would hold the input");
    EXPECT_EQ(fs::directory_iterator(st)->path().filename(), "N55W003.hgt.zip");
    EXPECT_TRUE(*read_file(input, kNoSizeLimit) == *before);
  }
  // An input inside an existing store.
  const fs::path s = dir / "s";
  ASSERT_EQ(run_relief(build(kEast, s)).exit_code, 0);
  fs::copy_file(kEast, s / "N55W003.hgt.zip");
  auto args = build((s / "N55W003.hgt.zip").string(), s);
  args.push_back("--overwrite");
  expect_one_line_error(run_relief(args), "would hold the input");
  EXPECT_TRUE(fs::exists(s / "N55W003.hgt.zip"));
  EXPECT_TRUE(fs::exists(s / "manifest.json"));
}

TEST(BuildNonFinite, InfiniteSamplesAreNodata) {
  ScratchDir dir("non_finite");
  std::vector<float> values = ramp();
  values[64 * 20 + 30] = INFINITY;
  values[64 * 40 + 10] = -INFINITY;
  write_float_raster(dir / "one_inf.tif", values);
  const fs::path s = dir / "s";
  auto r = run_relief(build((dir / "one_inf.tif").string(), s));
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_EQ(run_relief({"verify", s.string(), "-q"}).exit_code, 0);
  EXPECT_EQ(run_relief({"info", s.string()}).exit_code, 0);
  const auto m = nlohmann::json::parse(contents(s / "manifest.json"));
  const auto& stats = m.at("statistics");
  EXPECT_TRUE(stats.at("min").is_number()) << stats;
  EXPECT_TRUE(stats.at("max").is_number()) << stats;
  EXPECT_GE(stats.at("min").get<double>(), 99.0);
  EXPECT_LE(stats.at("max").get<double>(), 227.0);

  std::fill(values.begin(), values.end(), INFINITY);
  write_float_raster(dir / "all_inf.tif", values);
  expect_one_line_error(run_relief(build((dir / "all_inf.tif").string(), dir / "t")),
                        "no valid samples");
  EXPECT_FALSE(fs::exists(dir / "t" / "manifest.json"));
}

TEST(FuseWeights, HugeWeightsDoNotOverflow) {
  ScratchDir dir("fuse_weights");
  ASSERT_EQ(run_relief(build(kWest, dir / "a")).exit_code, 0);
  ASSERT_EQ(run_relief(build(kEast, dir / "b")).exit_code, 0);
  const std::vector<std::string> inputs = {(dir / "a").string(), (dir / "b").string()};
  auto fuse = [&](const std::string& out, const std::string& weights) {
    return run_relief(
        {"fuse", inputs[0], inputs[1], "-o", (dir / out).string(), "--weights", weights, "-q"});
  };
  ASSERT_EQ(fuse("unit", "1,1").exit_code, 0);
  auto r = fuse("huge", "1e308,1e308");
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_EQ(run_relief({"verify", (dir / "huge").string(), "-q"}).exit_code, 0);
  const auto unit = nlohmann::json::parse(contents(dir / "unit" / "manifest.json"));
  const auto huge = nlohmann::json::parse(contents(dir / "huge" / "manifest.json"));
  EXPECT_EQ(unit.at("statistics"), huge.at("statistics"));
  expect_one_line_error(fuse("bad", "1,inf"), "--weights");
}

// An input built to a coarser finest level than the others is upsampled into
// the finer levels, not left out of them (and out of the statistics).
TEST(FuseLevels, AnInputBuiltCoarserStillFillsTheFinerLevels) {
  ScratchDir dir("fuse_levels");
  ASSERT_EQ(run_relief(build(kWest, dir / "fine")).exit_code, 0);  // levels 0..5
  auto coarse = build(kEast, dir / "coarse");
  coarse[7] = "3";  // --max-level
  ASSERT_EQ(run_relief(coarse).exit_code, 0);
  auto both = build(kWest, dir / "both");
  both.insert(both.begin() + 2, kEast);
  ASSERT_EQ(run_relief(both).exit_code, 0);
  auto r = run_relief({"fuse", (dir / "fine").string(), (dir / "coarse").string(), "-o",
                       (dir / "fused").string(), "-q"});
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_EQ(run_relief({"verify", (dir / "fused").string(), "-q"}).exit_code, 0);
  auto fused = tiles::Store::open(dir / "fused");
  auto expected = tiles::Store::open(dir / "both");
  ASSERT_TRUE(fused && expected);
  for (int level = 4; level <= 5; ++level) {
    EXPECT_EQ(fused->index(level).size(), expected->index(level).size()) << level;
  }
  // Upsampled 4 x, the coarse input's edge moves by up to a coarse sample.
  EXPECT_NEAR(static_cast<double>(fused->manifest().stats.valid_count),
              static_cast<double>(expected->manifest().stats.valid_count),
              0.05 * static_cast<double>(expected->manifest().stats.valid_count));
  EXPECT_NEAR(fused->manifest().stats.mean, expected->manifest().stats.mean,
              0.02 * expected->manifest().stats.mean);
}

TEST(BuildMemory, BudgetsBeyondTheMachineAreRefused) {
  ScratchDir dir("memory");
  for (const char* size : {"99999999TiB", "1000TiB"}) {
    auto args = build(kEast, dir / "s");
    args.insert(args.end(), {"--memory", size});
    expect_one_line_error(run_relief(args), "--memory");
    EXPECT_FALSE(fs::exists(dir / "s"));
  }
}

TEST(StaleTemporaries, AKilledFuseOrExportLeavesNothingForTheNextRun) {
  ScratchDir dir("stale_fuse");
  ASSERT_EQ(run_relief(build(kWest, dir / "a")).exit_code, 0);
  ASSERT_EQ(run_relief(build(kEast, dir / "b")).exit_code, 0);
  const pid_t child = ::fork();
  if (child == 0) ::_exit(0);
  ::waitpid(child, nullptr, 0);  // `child` is now the id of a dead process
  const fs::path stale = dir / fmt::format("f{}{}", kTempMarker, child);
  fs::create_directories(stale / "3");
  std::ofstream(stale / "3" / "000.rtile") << "partial";
  auto r = run_relief(
      {"fuse", (dir / "a").string(), (dir / "b").string(), "-o", (dir / "f").string(), "-q"});
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_FALSE(fs::exists(stale));
  // A killed export's temporary GeoTIFF, likewise.
  const fs::path stale_tif = dir / fmt::format("e.tif{}{}", kTempMarker, child);
  std::ofstream(stale_tif) << "partial";
  r = run_relief({"export", (dir / "a").string(), "--level", "3", "-o", (dir / "e.tif").string()});
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_FALSE(fs::exists(stale_tif));
  EXPECT_TRUE(fs::exists(dir / "e.tif"));
}

}  // namespace
}  // namespace relief::testing
