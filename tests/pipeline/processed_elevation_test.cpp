// Elevation processed at draw time (pipeline/processed_elevation.h): a
// chain's tiles are `relief process`'s store of the same operators, tile for
// tile and error for error; a lens's samples take the lens chain inside the
// circle and the global chain outside, each by its own position, so tiles
// sharing a side hold the same samples there bit for bit; bad chains and
// lenses are one-line errors.
#include <gtest/gtest.h>

#include <cmath>
#include <cstring>

#include "../ingest/built_stores.h"
#include "../support/test_support.h"
#include "relief/pipeline/fused_elevation.h"
#include "relief/pipeline/process_store.h"
#include "relief/pipeline/processed_elevation.h"

namespace relief::testing {
namespace {

namespace fs = std::filesystem;

gpuprocess::OperatorChain chain(
    std::vector<std::pair<std::string, std::vector<std::string>>> steps) {
  gpuprocess::OperatorChain c;
  for (const auto& [op, params] : steps) {
    auto step = gpuprocess::make_step(op, params);
    if (!step) throw std::runtime_error(step.error().message);
    c.steps.push_back(std::move(*step));
  }
  return c;
}

Result<tiles::Store> processed(const tiles::Store& store, pipeline::ElevationProcessing p) {
  ThreadExecutor ex(2);
  return pipeline::process_elevation(store, store.root().string(), std::move(p), ex);
}

tiles::Store relief_process(const tiles::Store& in, const fs::path& out, const std::string& op,
                            const std::vector<std::string>& params) {
  ThreadExecutor ex(2);
  NullProgress progress;
  auto r = pipeline::process_store({in.root(), out, op, params}, ex, progress);
  if (!r) throw std::runtime_error(r.error().message);
  return std::move(*tiles::Store::open(out));
}

bool same(float a, float b) {
  return std::memcmp(&a, &b, sizeof a) == 0;
}

// The border processed tiles keep (what the hillshade reads beyond an edge).
constexpr int kKept = 2;

// Every tile of `drawn` (border kKept) holds the samples of `offline`'s tile
// (its wider border cropped) bit for bit, and the index entries agree:
// bounds, and the geometric errors of the processed pyramid.
void expect_same_store(const tiles::Store& drawn, const tiles::Store& offline) {
  ASSERT_EQ(drawn.manifest().border, kKept);
  ASSERT_EQ(drawn.manifest().max_level, offline.manifest().max_level);
  const int b = offline.manifest().border - kKept;
  size_t tiles = 0, errors = 0;
  for (int level = 0; level <= offline.manifest().max_level; ++level) {
    ASSERT_EQ(drawn.index(level).size(), offline.index(level).size()) << "level " << level;
    for (const tiles::IndexEntry& e : offline.index(level).entries()) {
      const tiles::IndexEntry* d = drawn.index(level).find(e.key);
      ASSERT_TRUE(d) << e.key.to_string();
      EXPECT_EQ(d->error, e.error) << e.key.to_string();
      EXPECT_EQ(d->min, e.min) << e.key.to_string();
      EXPECT_EQ(d->max, e.max) << e.key.to_string();
      EXPECT_EQ(d->valid_count, e.valid_count) << e.key.to_string();
      errors += e.error > 0;
      const tiles::Tile have = must_read(drawn, e.key), want = must_read(offline, e.key);
      const int w = have.raster.width(), h = have.raster.height(), ww = want.raster.width();
      for (int y = 0; y < h; ++y) {
        for (int x = 0; x < w; ++x) {
          const float v = have.raster.f32()[static_cast<size_t>(y) * w + x];
          const float u = want.raster.f32()[static_cast<size_t>(y + b) * ww + x + b];
          ASSERT_TRUE(same(v, u)) << e.key.to_string() << " sample " << x << "," << y << ": " << v
                                  << " vs " << u;
        }
      }
      ++tiles;
    }
  }
  EXPECT_GT(tiles, 20u);
  EXPECT_GT(errors, 10u);
}

TEST(ProcessedElevation, TilesAndErrorsAreThoseOfReliefProcess) {
  const tiles::Store& n42 = srtm_store("N42E001");
  ScratchDir dir("processed_elevation");
  const tiles::Store offline = relief_process(n42, dir / "gauss", "gauss", {"radius=3"});
  pipeline::ElevationProcessing p;
  p.chain = chain({{"gauss", {"radius=3"}}});
  auto drawn = processed(n42, p);
  ASSERT_TRUE(drawn) << drawn.error().message;
  expect_same_store(*drawn, offline);
  // The statistics are the processed finest level's.
  EXPECT_EQ(drawn->manifest().stats.valid_count, offline.manifest().stats.valid_count);
  EXPECT_NEAR(drawn->manifest().stats.mean, offline.manifest().stats.mean, 1e-6);
  EXPECT_EQ(drawn->manifest().stats.max, offline.manifest().stats.max);
}

// A chain is the operators one after the other: `relief process` twice.
TEST(ProcessedElevation, AChainIsReliefProcessRunOncePerOperator) {
  const tiles::Store& n42 = srtm_store("N42E001");
  ScratchDir dir("processed_elevation_chain");
  const tiles::Store median = relief_process(n42, dir / "median", "median", {"radius=2"});
  const tiles::Store offline = relief_process(median, dir / "mean", "mean", {"radius=4"});
  pipeline::ElevationProcessing p;
  p.chain = chain({{"median", {"radius=2"}}, {"mean", {"radius=4"}}});
  auto drawn = processed(n42, p);
  ASSERT_TRUE(drawn) << drawn.error().message;
  expect_same_store(*drawn, offline);
}

// Inside the lens the lens chain, outside the global chain, per sample by its
// position; and so two tiles sharing a side hold the same samples there.
TEST(ProcessedElevation, ALensMergesPerSampleAndNeighboursAgreeOnItsBorder) {
  const tiles::Store& n42 = srtm_store("N42E001");
  pipeline::ElevationProcessing p;
  p.chain = chain({{"mean", {"radius=1"}}});
  p.lenses.push_back(
      {1.42, 42.53, 9000, chain({{"gauss", {"radius=5"}}, {"median", {"radius=2"}}})});
  auto drawn = processed(n42, p);
  ASSERT_TRUE(drawn) << drawn.error().message;
  const geo::TileGrid& grid = n42.grid();
  // The chains' reference keeps one sample around what it takes as the
  // interior: given one sample less of border, the kept border.
  const int b = grid.border() - (kKept - 1), w = grid.width(), h = grid.height();
  const int pw = w + 2 * kKept, ph = h + 2 * kKept;
  const int max_level = n42.manifest().max_level;
  const auto& s = n42.manifest().stats;
  const process::GlobalStats stats{s.min, s.max, s.mean, s.stddev};
  InlineExecutor ex;
  size_t inside = 0, outside = 0, lens_differs = 0;
  for (int level = max_level - 3; level <= max_level; ++level) {
    const double factor = std::ldexp(1.0, max_level - level);
    for (const tiles::IndexEntry& e : n42.index(level).entries()) {
      const tiles::Tile in = must_read(n42, e.key), out = must_read(*drawn, e.key);
      auto global = gpuprocess::run_chain_cpu(gpuprocess::scale_chain(p.chain, factor), in.raster,
                                              b, &stats, ex);
      auto lens = gpuprocess::run_chain_cpu(gpuprocess::scale_chain(p.lenses[0].chain, factor),
                                            in.raster, b, &stats, ex);
      ASSERT_TRUE(global && lens);
      ASSERT_EQ(out.raster.width(), pw);
      for (int y = 0; y < ph; ++y) {
        for (int x = 0; x < pw; ++x) {
          const size_t i = static_cast<size_t>(y) * pw + x;
          const bool in_lens =
              pipeline::lens_distance_m(1.42, 42.53, grid.sample_lon(e.key, x - kKept),
                                        grid.sample_lat(e.key, y - kKept)) <= 9000;
          const float want = in_lens ? lens->f32()[i] : global->f32()[i];
          ASSERT_TRUE(same(out.raster.f32()[i], want))
              << e.key.to_string() << " sample " << x << "," << y << (in_lens ? " in" : " out");
          if (level == max_level && !std::isnan(want)) {
            (in_lens ? inside : outside) += 1;
            lens_differs += in_lens && !same(lens->f32()[i], global->f32()[i]);
          }
        }
      }
    }
  }
  EXPECT_GT(inside, 10000u);
  EXPECT_GT(outside, 100000u);
  EXPECT_GT(lens_differs, inside / 2);

  // Neighbours (east and south) share 2 kKept columns or rows: each one's
  // border is the other's edge interior, bit for bit, where the circle
  // crosses them.
  size_t crossed = 0;
  for (int level = max_level - 3; level <= max_level; ++level) {
    for (const tiles::IndexEntry& e : drawn->index(level).entries()) {
      const tiles::Tile a = must_read(*drawn, e.key);
      for (const auto& [dx, dy] : {std::pair{1, 0}, std::pair{0, 1}}) {
        const auto n = e.key.neighbour(dx, dy);
        if (!n || !drawn->has_tile(*n)) continue;
        const tiles::Tile c = must_read(*drawn, *n);
        const int len = dx ? ph : pw;
        bool in_seen = false, out_seen = false;
        for (int k = kKept; k + kKept < len; ++k) {
          // a's sample at w + j (its last interiors, then its east or south
          // border) is c's at j (its west or north border, then its first
          // interiors).
          for (int j = 0; j < 2 * kKept; ++j) {
            const int ai = (dx ? w : h) + j, ci = j;
            const size_t ia =
                dx ? static_cast<size_t>(k) * pw + ai : static_cast<size_t>(ai) * pw + k;
            const size_t ic =
                dx ? static_cast<size_t>(k) * pw + ci : static_cast<size_t>(ci) * pw + k;
            ASSERT_TRUE(same(a.raster.f32()[ia], c.raster.f32()[ic]))
                << e.key.to_string() << " and " << n->to_string() << " at " << k << ", " << j;
          }
          const double lon =
              dx ? grid.sample_lon(e.key, w - 0.5) : grid.sample_lon(e.key, k - kKept);
          const double lat =
              dx ? grid.sample_lat(e.key, k - kKept) : grid.sample_lat(e.key, h - 0.5);
          (pipeline::lens_distance_m(1.42, 42.53, lon, lat) <= 9000 ? in_seen : out_seen) = true;
        }
        crossed += in_seen && out_seen;
      }
    }
  }
  EXPECT_GE(crossed, 4u);
}

TEST(ProcessedElevation, BadChainsAndLensesAreOneLineErrors) {
  const tiles::Store& n42 = srtm_store("N42E001");
  struct Case {
    gpuprocess::OperatorChain chain;
    std::vector<pipeline::ElevationLens> lenses;
    std::string needle;
  };
  const std::vector<Case> cases = {
      {chain({{"lee", {}}}), {}, "operator lee expects SAR amplitude"},
      {chain({{"amplitude-to-db", {}}}), {}, "operator amplitude-to-db expects"},
      {chain({{"linear", {}}}), {}, "operator linear expects"},
      {chain({{"ext-schlick", {}}}), {}, "operator ext-schlick expects"},
      {chain({{"median", {"radius=9"}}}), {}, "median: needs a 9-sample margin"},
      {chain({{"median", {"radius=8"}}}), {}, "more than the 7 of the store's 9-sample overlap"},
      {chain({{"gauss", {"radius=5"}}, {"mean", {"radius=3"}}}), {}, "mean: needs a 3-sample"},
      {{}, {{1.5, 42.5, 0, {}}}, "elevation lens radius must be > 0 m, not 0"},
      {{}, {{1.5, 42.5, -5, chain({{"mean", {}}})}}, "elevation lens radius must be > 0 m"},
      {{}, {{1.5, 42.5, 500, chain({{"frost", {}}})}}, "(elevation lens): operator frost"},
      {{}, {{1.5, 42.5, 500, chain({{"mean", {"radius=9"}}})}}, "(elevation lens): mean: needs"},
  };
  for (const Case& c : cases) {
    auto r = processed(n42, {c.chain, c.lenses});
    ASSERT_FALSE(r) << c.needle;
    EXPECT_NE(r.error().message.find(c.needle), std::string::npos) << r.error().message;
    EXPECT_EQ(r.error().message.find('\n'), std::string::npos) << r.error().message;
    EXPECT_TRUE(r.error().message.starts_with(n42.root().string())) << r.error().message;
  }

  ingest::BuildOptions o;
  o.inputs = {data("sar/umbra_mount_yasur.tif")};
  o.kind = tiles::DatasetKind::Sar;
  auto sar = processed(built_store("umbra", o), {chain({{"mean", {}}}), {}});
  ASSERT_FALSE(sar);
  EXPECT_NE(sar.error().message.find("holds sar data"), std::string::npos) << sar.error().message;

  // Layers of different depths (a store of sparse depth): not yet.
  ingest::BuildOptions coarse;
  coarse.inputs = {data("srtm/N42E001.hgt.zip")};
  coarse.kind = tiles::DatasetKind::Elevation;
  coarse.max_level = n42.manifest().max_level - 2;
  std::vector<pipeline::ElevationLayer> layers;
  layers.push_back({"coarse", built_store("n42-coarse", coarse)});
  layers.push_back({"n42", n42});
  ThreadExecutor ex(2);
  auto sparse = pipeline::fuse_elevation_layers(std::move(layers), pipeline::FuseMode::First, ex);
  ASSERT_TRUE(sparse) << sparse.error().message;
  auto r = pipeline::process_elevation(*sparse, "sparse", {chain({{"mean", {}}}), {}}, ex);
  ASSERT_FALSE(r);
  EXPECT_NE(r.error().message.find("different depths"), std::string::npos) << r.error().message;
}

}  // namespace
}  // namespace relief::testing
