// A manifest that contradicts itself or its tiles (imagery over float32
// samples, a PNG codec for elevations, a swapped extent, statistics that do not
// count the tiles' samples) fails verify, and the store reader refuses it.
#include <gtest/gtest.h>

#include <array>
#include <cmath>
#include <cstring>
#include <fstream>
#include <functional>
#include <span>

#include <nlohmann/json.hpp>

#include "relief/tiles/tile_file.h"
#include "test_support.h"

namespace relief::testing {
namespace {
namespace fs = std::filesystem;
using nlohmann::json;

class ManifestConsistency : public ::testing::Test {
 protected:
  static void SetUpTestSuite() {
    dir_ = new ScratchDir("manifest_consistency");
    ASSERT_EQ(run_relief({"build", data("srtm/N42E001.hgt.zip"), "--kind", "elevation", "-o",
                          (dir_->path() / "good").string(), "--min-level", "8", "-q"})
                  .exit_code,
              0);
  }
  static void TearDownTestSuite() {
    delete dir_;
    dir_ = nullptr;
  }
  // A copy of the good store whose manifest `edit` changed.
  static std::string tampered(const std::string& name, const std::function<void(json&)>& edit) {
    const fs::path store = dir_->path() / name;
    fs::remove_all(store);
    fs::copy(dir_->path() / "good", store, fs::copy_options::recursive);
    json m;
    std::ifstream(store / "manifest.json") >> m;
    edit(m);
    std::ofstream(store / "manifest.json") << m.dump(2);
    return store.string();
  }
  static inline ScratchDir* dir_ = nullptr;
};

TEST_F(ManifestConsistency, ImageryKindOverFloatSamplesIsRefused) {
  const std::string store = tampered("imagery_kind", [](json& m) { m["kind"] = "imagery"; });
  const std::string manifest = store + "/manifest.json";
  EXPECT_TRUE(is_one_line_error(run_relief({"verify", store, "-q"}),
                                manifest + ": kind imagery needs uint8 samples, not float32"));
  EXPECT_TRUE(is_one_line_error(run_relief({"info", store}), manifest));
  EXPECT_TRUE(is_one_line_error(
      run_relief({"export", store, "--level", "9", "-o", (dir_->path() / "x.tif").string()}),
      manifest));
  EXPECT_FALSE(fs::exists(dir_->path() / "x.tif"));
}

TEST_F(ManifestConsistency, ContradictoryFieldsAreRefused) {
  struct Case {
    const char* name;
    std::function<void(json&)> edit;
    const char* needle;
  };
  const Case cases[] = {
      {"sar_uint8",
       [](json& m) {
         m["kind"] = "sar";
         m["sample_type"] = "uint8";
       },
       "kind sar needs float32 samples"},
      {"bands", [](json& m) { m["bands"] = 4; }, "float32 samples come in 1 band(s), not 4"},
      {"codec", [](json& m) { m["codec"]["name"] = "png"; }, "codec png cannot store float32"},
      {"max_error", [](json& m) { m["codec"]["max_error"] = -1; }, "max_error -1"},
      {"extent", [](json& m) { std::swap(m["extent"]["west"], m["extent"]["east"]); }, "extent"},
      {"stats", [](json& m) { m["statistics"]["min"] = 5000; }, "statistics min 5000"},
      // Issue 42 item 6: what the probe's manifests got through.
      {"registration", [](json& m) { m["tile"]["registration"] = "grid-point"; },
       "tile registration 'grid-point' is not cell-centre"},
      {"nodata", [](json& m) { m["nodata"] = "alpha=0"; }, "nodata 'alpha=0' is not float32"},
      {"extent_1e308", [](json& m) { m["extent"]["east"] = 1e308; }, "E 1e+308"},
      {"extent_empty", [](json& m) { m["extent"]["east"] = m["extent"]["west"]; },
       "is not west < east"},
      {"extent_pole", [](json& m) { m["extent"]["north"] = 95; }, "N 95 is not"},
      {"stats_huge", [](json& m) { m["statistics"]["max"] = 1e308; }, "max 1e+308 mean 1372"},
  };
  for (const auto& c : cases) {
    const std::string store = tampered(c.name, c.edit);
    const auto r = run_relief({"verify", store, "-q"});
    EXPECT_TRUE(is_one_line_error(r, c.needle)) << c.name << ": " << r.err;
  }
}

TEST_F(ManifestConsistency, StatisticsMustCountTheFinestTiles) {
  const std::string store = tampered("count", [](json& m) {
    m["statistics"]["valid_samples"] = m["statistics"]["valid_samples"].get<uint64_t>() + 1;
  });
  const auto r = run_relief({"verify", store, "-q"});
  EXPECT_TRUE(is_one_line_error(r, "statistics count")) << r.err;
  EXPECT_EQ(run_relief({"verify", (dir_->path() / "good").string(), "-q"}).exit_code, 0);
}

// The manifest agrees with itself but not with the tiles: one line naming
// the manifest, not one per tile.
TEST_F(ManifestConsistency, AManifestThatContradictsTheTilesFailsVerify) {
  struct Case {
    const char* name;
    std::function<void(json&)> edit;
    const char* needle;
  };
  const Case cases[] = {
      {"lerc", [](json& m) { m["codec"]["name"] = "lerc"; }, "codec lerc contradicts"},
      {"elsewhere",
       [](json& m) {
         m["extent"]["west"] = 100;
         m["extent"]["east"] = 101;
       },
       "extent W 100 S"},
      {"max_above", [](json& m) { m["statistics"]["max"] = 3100; },
       "statistics min 349.7852783203125 max 3100 are outside the finest level's samples"},
  };
  for (const auto& c : cases) {
    const std::string store = tampered(c.name, c.edit);
    const auto r = run_relief({"verify", store, "-q"});
    EXPECT_TRUE(is_one_line_error(r, store + "/manifest.json: " + c.needle))
        << c.name << ": " << r.err;
  }
}

// A tile header whose statistics are NaN, infinite or contradict each other
// (checksum recomputed) is refused by every reader, naming the tile.
TEST_F(ManifestConsistency, TileStatisticsThatAreNotNumbersAreRefused) {
  const std::pair<size_t, double> cases[] = {{24, NAN}, {32, INFINITY}, {24, -INFINITY},
                                             {40, NAN}, {40, 1e300},    {48, INFINITY}};
  for (const auto& [offset, value] : cases) {
    const std::string store = tampered("tile_stats", [](json&) {});
    fs::path tile;
    for (const auto& e : fs::recursive_directory_iterator(store)) {
      if (e.path().extension() == ".rtile" && (tile.empty() || e.path() < tile)) tile = e.path();
    }
    std::fstream f(tile, std::ios::in | std::ios::out | std::ios::binary);
    std::array<char, 80> header{};
    f.read(header.data(), header.size());
    std::memcpy(header.data() + offset, &value, sizeof value);
    const uint32_t crc =
        tiles::crc32_of(std::as_bytes(std::span<const char>(header.data(), size_t{76})));
    std::memcpy(header.data() + 76, &crc, sizeof crc);
    f.seekp(0);
    f.write(header.data(), header.size());
    f.close();
    const auto r = run_relief({"verify", store, "-q"});
    EXPECT_TRUE(is_one_line_error(r, tile.string() + ": tile header statistics"))
        << offset << " " << value << ": " << r.err;
  }
}

// Without --bbox the box is the store's extent: an error names it, not --bbox.
TEST_F(ManifestConsistency, ExportWithoutBboxBlamesTheExtentNotTheOption) {
  const std::string store = tampered("wide", [](json& m) {
    m["extent"] = {{"west", -170}, {"south", -80}, {"east", 170}, {"north", 80}};
  });
  const auto r = run_relief(
      {"export", store, "--level", "10", "-o", (dir_->path() / "wide.tif").string(), "-q"});
  EXPECT_TRUE(is_one_line_error(r, store + ": the store's extent, exported without --bbox"))
      << r.err;
  EXPECT_EQ(r.err.find("--bbox:"), std::string::npos) << r.err;
}

}  // namespace
}  // namespace relief::testing
