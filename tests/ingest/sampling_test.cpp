// The finest level reproduces GDAL's bilinear sample of the input.
#include <gtest/gtest.h>

#include <cmath>
#include <random>

#include "../support/test_support.h"
#include "built_stores.h"
#include "gdal_reference.h"

namespace relief::testing {
namespace {

// Compares the store against an independent bilinear interpolation of the
// source at random sample centres inside `box`; returns the number compared.
int compare_with_bilinear(const tiles::Store& store, const std::vector<SourceGrid>& sources,
                          geo::GeoBox box, double tolerance, unsigned seed) {
  const int level = store.manifest().max_level;
  const auto& grid = store.grid();
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> lon(box.west, box.east), lat(box.south, box.north);
  int compared = 0;
  for (int n = 0; n < 1500; ++n) {
    // Snap to a sample centre of the finest level: that is what the store holds.
    const geo::SampleIndex s = grid.locate(level, lon(rng), lat(rng));
    const double x = grid.sample_lon(s.tile, s.i), y = grid.sample_lat(s.tile, s.j);
    double expected = 0;
    bool found = false;
    for (const auto& src : sources) {
      if (bilinear(src, x, y, expected)) {
        found = true;
        break;
      }
    }
    if (!found) continue;
    auto v = store.sample(x, y, level);
    EXPECT_TRUE(v.has_value()) << v.error().message;
    EXPECT_TRUE(v->has_value()) << "nodata at " << x << "," << y;
    if (!v->has_value()) continue;
    EXPECT_NEAR(**v, expected, tolerance) << "at lon " << x << " lat " << y;
    ++compared;
  }
  return compared;
}

TEST(Sampling, LosslessFinestLevelEqualsGdalBilinear) {
  const auto& store = pyrenees_store();
  EXPECT_EQ(store.manifest().max_level, 10);
  std::vector<SourceGrid> sources;
  for (const auto& in : pyrenees_inputs())
    sources.push_back(
        read_source("/vsizip/" + in + "/" + std::filesystem::path(in).stem().string()));
  const int n = compare_with_bilinear(store, sources, {1.0, 41.0, 2.0, 43.0}, 1e-3, 1);
  EXPECT_GT(n, 1300);
}

TEST(Sampling, LercFinestLevelIsWithinMaxError) {
  ingest::BuildOptions o;
  o.inputs = {data("srtm/N42E001.hgt.zip")};
  o.kind = tiles::DatasetKind::Elevation;
  o.max_error = 0.5;
  o.min_level = 8;
  const auto& store = built_store("pyrenees_lerc", o);
  EXPECT_EQ(store.manifest().codec.codec, tiles::Codec::Lerc);
  std::vector<SourceGrid> sources = {
      read_source("/vsizip/" + data("srtm/N42E001.hgt.zip") + "/N42E001.hgt")};
  const int n = compare_with_bilinear(store, sources, {1.0, 42.0, 2.0, 43.0}, 0.5 + 1e-3, 2);
  EXPECT_GT(n, 1300);
  // Lossy but bounded, and smaller than lossless.
  uint64_t lerc_bytes = store.index(10).total_bytes();
  uint64_t zstd_bytes = 0;
  for (const auto& e : pyrenees_store().index(10).entries()) {
    if (store.has_tile(e.key)) zstd_bytes += e.file_bytes;
  }
  EXPECT_LT(lerc_bytes, zstd_bytes / 2);
}

}  // namespace
}  // namespace relief::testing
