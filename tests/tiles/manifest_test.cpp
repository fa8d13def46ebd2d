#include "relief/tiles/manifest.h"

#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>

#include <string>
#include <utility>
#include <vector>
#include "relief/tiles/store.h"
#include "relief/tiles/store_layout.h"

namespace relief::tiles {

TEST(Manifest, JsonRoundTrip) {
  Manifest m;
  m.kind = DatasetKind::Sar;
  m.units = "amplitude";
  m.min_level = 2;
  m.max_level = 17;
  m.extent = {169.4, -19.6, 169.5, -19.5};
  m.stats = {0, 255, 32.25, 32.45, 4000000};
  m.codec = {Codec::Lerc, 0.25, 90, 3};
  m.sources.push_back({"a.tif", "EPSG:32759", 2000, 2000, 1, "Byte"});
  auto back = Manifest::from_json(m.to_json(), "m");
  ASSERT_TRUE(back) << back.error().message;
  EXPECT_EQ(back->kind, DatasetKind::Sar);
  EXPECT_EQ(back->max_level, 17);
  EXPECT_EQ(back->codec.codec, Codec::Lerc);
  EXPECT_DOUBLE_EQ(back->codec.max_error, 0.25);
  EXPECT_DOUBLE_EQ(back->stats.stddev, 32.45);
  EXPECT_EQ(back->sources.at(0).crs, "EPSG:32759");
  EXPECT_EQ(back->extent.south, -19.6);
}

TEST(Manifest, BadManifestsNameTheFile) {
  for (const char* text : {"", "{}", "[1,2]", R"({"format":"other"})",
                           R"({"format":"relief-store","format_version":99})"}) {
    auto m = Manifest::from_json(text, "store/manifest.json");
    ASSERT_FALSE(m) << text;
    EXPECT_NE(m.error().message.find("store/manifest.json"), std::string::npos);
  }
}

TEST(Manifest, FormatOneNamesTheUpgrade) {
  Manifest m;
  m.format_version = 1;
  auto back = Manifest::from_json(m.to_json(), "/data/pyr/manifest.json");
  ASSERT_FALSE(back);
  EXPECT_EQ(back.error().message,
            "/data/pyr/manifest.json: the store predates geometric errors (store format version "
            "1); upgrade it with `relief upgrade /data/pyr`");
}

// JSON has no infinity: written, it would read back as null and the store
// would open nowhere. The writer refuses, naming the field, and writes nothing.
TEST(Manifest, NonFiniteValuesAreNeverWritten) {
  namespace fs = std::filesystem;
  const fs::path dir = fs::temp_directory_path() / "relief_manifest_non_finite";
  fs::remove_all(dir);
  fs::create_directories(dir);
  Manifest m;
  m.stats = {0, 100, 50, 10, 1000};
  ASSERT_TRUE(write_manifest(dir, m));
  fs::remove(dir / kManifestName);
  for (double bad : {INFINITY, -INFINITY, NAN}) {
    Manifest b = m;
    b.stats.min = bad;
    auto st = write_manifest(dir, b);
    ASSERT_FALSE(st);
    EXPECT_NE(st.error().message.find("statistics min"), std::string::npos) << st.error().message;
    b = m;
    b.stats.mean = bad;
    EXPECT_FALSE(write_manifest(dir, b));
    b = m;
    b.extent.east = bad;
    EXPECT_FALSE(write_manifest(dir, b));
    EXPECT_FALSE(fs::exists(dir / kManifestName));
  }
  EXPECT_TRUE(fs::is_empty(dir));  // no temporary left either
  fs::remove_all(dir);
}

// Numbers that do not fit their field are errors, not undefined behaviour:
// nlohmann's get<int>() of 1e300 is a bare static_cast, and a tile height
// above 2^30 made the power-of-two search shift by 32 (UBSan under
// fuzz/manifest.cpp; the inputs are in fuzz/regressions/manifest/).
TEST(Manifest, NumbersOutOfRangeAreErrors) {
  const std::string good = Manifest{}.to_json();
  ASSERT_TRUE(Manifest::from_json(good, "m"));
  auto with = [&good](const std::string& from, const std::string& to) {
    std::string text = good;
    const size_t at = text.find(from);
    EXPECT_NE(at, std::string::npos) << from;
    return text.replace(at, from.size(), to);
  };
  for (const auto& [from, to] : std::vector<std::pair<std::string, std::string>>{
           {"\"bands\": 1,", "\"bands\": 1e300,"},
           {"\"bands\": 1,", "\"bands\": 1.5,"},
           {"\"bands\": 1,", "\"bands\": 4294967297,"},
           {"\"height\": 256,", "\"height\": 1073741825,"},
           {"\"height\": 256,", "\"height\": 1073741824,"},
           {"\"width\": 512", "\"width\": 2147483648"},
           {"\"border\": 9,", "\"border\": 2147483647,"},
           {"\"border\": 9,", "\"border\": -1,"},
           {"\"max\": 0,", "\"max\": 1e10,"},
           {"\"valid_samples\": 0", "\"valid_samples\": -1"},
           {"\"quality\": 90", "\"quality\": 9e99"}}) {
    auto m = Manifest::from_json(with(from, to), "store/manifest.json");
    EXPECT_FALSE(m) << to;
    if (!m) {
      EXPECT_NE(m.error().message.find("store/manifest.json"), std::string::npos);
    }
  }
  // The largest tile a tile file can hold still reads.
  std::string largest = with("\"height\": 256,", "\"height\": 16384,");
  largest.replace(largest.find("\"width\": 512"), 13, "\"width\": 32768");
  EXPECT_TRUE(Manifest::from_json(largest, "m"));
}

}  // namespace relief::tiles
