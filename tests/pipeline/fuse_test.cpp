// `relief fuse`: two SRTM tiles fused equal the store built from both; weights,
// void filling, index bounds combined without scanning, and bad input.
#include <gtest/gtest.h>

#include <fmt/format.h>

#include <cmath>
#include <cstring>

#include "../ingest/built_stores.h"
#include "../support/test_support.h"
#include "level_image.h"
#include "relief/pipeline/fuse_stores.h"
#include "relief/tiles/verify.h"

namespace relief::testing {
namespace {

namespace fs = std::filesystem;

tiles::Store fuse(std::vector<fs::path> inputs, const fs::path& out, std::vector<double> weights,
                  pipeline::FuseMode mode = pipeline::FuseMode::Blend) {
  ThreadExecutor ex(2);
  NullProgress progress;
  auto r = pipeline::fuse_stores({std::move(inputs), std::move(weights), mode, out}, ex, progress);
  if (!r) throw std::runtime_error(r.error().message);
  return std::move(*tiles::Store::open(out));
}

TEST(Fuse, TwoTilesFusedMatchTheStoreBuiltFromBoth) {
  const tiles::Store &north = srtm_store("N42E001"), &south = srtm_store("N41E001");
  ScratchDir dir("fuse");
  const tiles::Store fused = fuse({north.root(), south.root()}, dir / "f", {});
  const tiles::Store& both = pyrenees_store();
  ASSERT_EQ(fused.manifest().max_level, both.manifest().max_level);
  const int level = both.manifest().max_level;
  const LevelImage a = read_level(fused, level), b = read_level(both, level);
  ASSERT_EQ(a.width, b.width);
  ASSERT_EQ(a.x0, b.x0);
  double worst = 0;
  size_t valid = 0, differing = 0;
  for (size_t k = 0; k < a.v.size(); ++k) {
    ASSERT_EQ(std::isnan(a.v[k]), std::isnan(b.v[k])) << "sample " << k;
    if (std::isnan(a.v[k])) continue;
    ++valid;
    const double d = std::abs(double(a.v[k]) - b.v[k]);
    worst = std::max(worst, d);
    if (d > 1e-3) ++differing;
  }
  EXPECT_GT(valid, 2'000'000u);
  // Only the samples of the shared edge at 42 N differ: there the mosaic
  // interpolates across both tiles, the fusion averages two one-sided values.
  EXPECT_LT(worst, 20.0);
  EXPECT_LT(differing, valid / 500);
  EXPECT_EQ(fused.manifest().sources.size(), 2u);
  // The fused store carries its own geometric errors: verify recomputes them.
  ThreadExecutor ex(2);
  NullProgress progress;
  const tiles::VerifyReport report = tiles::verify_store(fused.root(), ex, progress);
  EXPECT_TRUE(report.ok()) << (report.ok() ? "" : report.problems.front());
  EXPECT_GT(fused.index(level - 1).entries().front().error, 0.0f);
}

TEST(Fuse, WeightsModesAndBoundsWithoutScanning) {
  const tiles::Store &north = srtm_store("N42E001"), &south = srtm_store("N41E001");
  ScratchDir dir("fuse_weights");
  // A store fused with itself under any weights is itself.
  const tiles::Store same = fuse({north.root(), north.root()}, dir / "same", {1, 3});
  for (const auto& e : north.index(north.manifest().max_level).entries()) {
    const auto x = must_read(north, e.key), y = must_read(same, e.key);
    ASSERT_EQ(std::memcmp(x.raster.bytes().data(), y.raster.bytes().data(), x.raster.byte_size()),
              0);
  }
  // Weighted blend and void filling where both have data.
  const tiles::Store blend = fuse({north.root(), south.root()}, dir / "blend", {3, 1});
  const tiles::Store first =
      fuse({north.root(), south.root()}, dir / "first", {}, pipeline::FuseMode::First);
  const int level = 8;
  for (const auto& e : blend.index(level).entries()) {
    const auto* n = north.index(level).find(e.key);
    const auto* s = south.index(level).find(e.key);
    // Bounds come from the inputs' indices and contain the fused samples.
    const float lo = std::min(n ? n->min : INFINITY, s ? s->min : INFINITY);
    const float hi = std::max(n ? n->max : -INFINITY, s ? s->max : -INFINITY);
    EXPECT_LE(e.min, lo);
    EXPECT_GE(e.max, hi);
    const auto t = must_read(blend, e.key);
    EXPECT_GE(t.header.stats.min, e.min);
    EXPECT_LE(t.header.stats.max, e.max);
    if (!n || !s) continue;
    const auto tn = must_read(north, e.key), ts = must_read(south, e.key),
               tf = must_read(first, e.key);
    for (size_t k = 0; k < tn.raster.pixel_count(); ++k) {
      const float vn = tn.raster.f32()[k], vs = ts.raster.f32()[k];
      const float vb = t.raster.f32()[k], vf = tf.raster.f32()[k];
      if (!std::isnan(vn) && !std::isnan(vs)) {
        ASSERT_FLOAT_EQ(vb, static_cast<float>((3.0 * vn + vs) / 4));
      }
      if (!std::isnan(vn)) {
        ASSERT_EQ(vf, vn);
      } else if (!std::isnan(vs)) {
        ASSERT_EQ(vf, vs);
        ASSERT_EQ(vb, vs);
      }
    }
  }
}

TEST(Fuse, BadInputIsRefused) {
  ScratchDir dir("fuse_bad");
  ThreadExecutor ex(2);
  NullProgress progress;
  ingest::BuildOptions o;
  o.inputs = {data("sar/umbra_mount_yasur.tif")};
  o.kind = tiles::DatasetKind::Sar;
  const fs::path sar = built_store("umbra", o).root(), dem = srtm_store("N42E001").root();
  auto expect_error = [&](pipeline::FuseOptions f, const std::string& needle) {
    auto r = pipeline::fuse_stores(f, ex, progress);
    ASSERT_FALSE(r);
    EXPECT_NE(r.error().message.find(needle), std::string::npos) << r.error().message;
    EXPECT_FALSE(fs::exists(f.output));
  };
  expect_error({{dem}, {}, pipeline::FuseMode::Blend, dir / "a"}, "at least two");
  expect_error({{dem, sar}, {}, pipeline::FuseMode::Blend, dir / "b"}, "holds sar data");
  expect_error({{dem, dem}, {1}, pipeline::FuseMode::Blend, dir / "c"}, "1 weights for 2");
  expect_error({{dem, dem}, {1, -2}, pipeline::FuseMode::Blend, dir / "d"}, "not > 0");
  expect_error({{dem, dir / "nope"}, {}, pipeline::FuseMode::Blend, dir / "e"}, "nope");
  EXPECT_TRUE(fs::is_empty(dir.path()));
}

// A global DEM fused with a local one would be upsampled to the local one's
// finest level everywhere: refused before anything is written.
TEST(Fuse, InputsOfVeryDifferentResolutionAreRefusedUnlessAllowed) {
  ScratchDir dir("fuse_upsampling");
  ThreadExecutor ex(2);
  NullProgress progress;
  ingest::BuildOptions o;
  o.inputs = {data("srtm/N42E001.hgt.zip")};
  o.kind = tiles::DatasetKind::Elevation;
  o.max_level = srtm_store("N41E001").manifest().max_level - 1;
  const fs::path near = built_store("N42E001-one-coarser", o).root();
  o.max_level = *o.max_level - 3;
  const fs::path coarse = built_store("N42E001-four-coarser", o).root();
  const fs::path fine = srtm_store("N41E001").root();
  pipeline::FuseOptions f{{near, coarse}, {}, pipeline::FuseMode::First, dir / "fused"};
  auto r = pipeline::fuse_stores(f, ex, progress);
  ASSERT_FALSE(r);
  EXPECT_NE(
      r.error().message.find(fmt::format("N42E001-four-coarser stops at level {}", *o.max_level)),
      std::string::npos)
      << r.error().message;
  EXPECT_NE(r.error().message.find("--allow-upsampling"), std::string::npos);
  EXPECT_TRUE(fs::is_empty(dir.path()));
  // One level apart is the ordinary case: fused without being asked.
  EXPECT_TRUE(pipeline::fuse_stores({{fine, near}, {}, pipeline::FuseMode::First, dir / "near"}, ex,
                                    progress));
  f.allow_upsampling = true;
  f.output = dir / "allowed";
  EXPECT_TRUE(pipeline::fuse_stores(f, ex, progress));
}

}  // namespace
}  // namespace relief::testing
