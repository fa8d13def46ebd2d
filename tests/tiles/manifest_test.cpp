#include "relief/tiles/manifest.h"

#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>

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

}  // namespace relief::tiles
