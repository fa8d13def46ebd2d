// A manifest that contradicts itself or its tiles (imagery over float32
// samples, a PNG codec for elevations, a swapped extent, statistics that do not
// count the tiles' samples) fails verify, and the store reader refuses it.
#include <gtest/gtest.h>

#include <fstream>
#include <functional>

#include <nlohmann/json.hpp>

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

}  // namespace
}  // namespace relief::testing
