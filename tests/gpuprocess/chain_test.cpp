// Chains of operators on the GPU equal the CPU chain; the overlap border
// limits the chain's radii with a clear error; processed neighbours agree on
// the one-sample border the output keeps.
#include <gtest/gtest.h>

#include <cmath>
#include <cstring>

#include "../ingest/built_stores.h"
#include "gpu_fixture.h"

namespace relief::testing {
namespace {

using gpuprocess::OperatorChain;

TEST(GpuChain, ChainsOfTwoOrThreeOperatorsEqualTheCpuChain) {
  // Intensity in, Lee on intensities (no longer integers), amplitude out.
  expect_gpu_equals_cpu(chain_of({{"amplitude-to-intensity", {}},
                                  {"lee", {"radius=3", "looks=2"}},
                                  {"intensity-to-amplitude", {}}}),
                        1e-4);
  expect_gpu_equals_cpu(chain_of({{"lee", {"radius=3"}}, {"linear", {}}}), 1e-4);
  expect_gpu_equals_cpu(chain_of({{"median", {"radius=2"}},
                                  {"gauss", {"radius=2"}},
                                  {"ext-schlick", {"max_radius=3", "d=0.7"}}}),
                        1e-4);
  expect_gpu_equals_cpu(chain_of({{"mean", {"radius=1"}}, {"amplitude-to-db", {}}}), 1e-4);
  // dB and back: db-to-amplitude on the range it is meant for.
  expect_gpu_equals_cpu(chain_of({{"amplitude-to-db", {}}, {"db-to-amplitude", {}}}), 1e-4);
  // The wavelet's own passes inside a chain: margin 6 + 2, the whole border.
  expect_gpu_equals_cpu(
      chain_of({{"wavelet", {"levels=2"}}, {"ext-reinhard-devlin", {"max_radius=2"}}}), 1e-4, 1);
}

TEST(GpuChain, OutputIsTheInteriorWithAOneSampleBorder) {
  const tiles::Store& store = sar_store();
  const int border = store.manifest().border;
  const auto& e = store.index(store.manifest().max_level).entries().front();
  const tiles::Tile tile = must_read(store, e.key);
  const process::GlobalStats stats = sar_stats();
  // Margin 4 + 4 = 8: the whole 9-sample border but the one kept.
  const OperatorChain chain = chain_of({{"lee", {"radius=4"}}, {"mean", {"radius=4"}}});
  auto out = gpu().run(chain, tile.raster, border, &stats);
  ASSERT_TRUE(out) << out.error().message;
  EXPECT_EQ(out->width(), tile.header.interior_width() + 2);
  EXPECT_EQ(out->height(), tile.header.interior_height() + 2);
  auto none = gpu().run({}, tile.raster, border, nullptr);  // no step: a copy, cropped
  ASSERT_TRUE(none);
  ASSERT_EQ(none->width(), out->width());
  for (int y = 0; y < none->height(); ++y) {
    const float* want =
        tile.raster.f32().data() + (y + border - 1) * tile.raster.width() + border - 1;
    ASSERT_EQ(
        std::memcmp(none->f32().data() + y * none->width(), want, none->width() * sizeof(float)), 0)
        << "row " << y;
  }
}

TEST(GpuChain, RadiiBeyondTheOverlapBorderAreRefused) {
  const tiles::Store& store = sar_store();
  const int border = store.manifest().border;
  ASSERT_EQ(border, 9);
  const auto& e = store.index(store.manifest().max_level).entries().front();
  const tiles::Tile tile = must_read(store, e.key);
  const process::GlobalStats stats = sar_stats();
  InlineExecutor ex;
  for (const OperatorChain& chain : {chain_of({{"lee", {"radius=9"}}}),
                                     chain_of({{"lee", {"radius=4"}}, {"mean", {"radius=5"}}}),
                                     chain_of({{"ext-schlick", {"max_radius=10"}}})}) {
    auto got = gpu().run(chain, tile.raster, border, &stats);
    ASSERT_FALSE(got);
    EXPECT_NE(got.error().message.find("overlap border"), std::string::npos) << got.error().message;
    EXPECT_EQ(got.error().message.find('\n'), std::string::npos);
    auto cpu = gpuprocess::run_chain_cpu(chain, tile.raster, border, &stats, ex);
    ASSERT_FALSE(cpu);
    EXPECT_EQ(cpu.error().message, got.error().message);
  }
  auto second = gpu().run(chain_of({{"lee", {"radius=4"}}, {"mean", {"radius=5"}}}), tile.raster,
                          border, &stats);
  EXPECT_EQ(second.error().message.rfind("mean:", 0), 0u) << second.error().message;
  // Three wavelet scales need 14 samples.
  auto wavelet3 = gpu().run(chain_of({{"wavelet", {"levels=3"}}}), tile.raster, border, &stats);
  ASSERT_FALSE(wavelet3);
  EXPECT_EQ(wavelet3.error().message.rfind("wavelet: needs a 14-sample margin", 0), 0u);
  // Radii are per level: one level coarser, radius 9 becomes 5 and fits.
  const auto coarser = gpuprocess::scale_chain(chain_of({{"lee", {"radius=9"}}}), 2);
  EXPECT_TRUE(gpu().run(coarser, tile.raster, border, &stats));
}

TEST(GpuChain, BadChainsAreOneLineErrors) {
  const tiles::Store& store = sar_store();
  const int border = store.manifest().border;
  const auto& e = store.index(store.manifest().max_level).entries().front();
  const tiles::Tile tile = must_read(store, e.key);
  auto unknown = gpuprocess::make_step("sharpen", {});
  ASSERT_FALSE(unknown);
  EXPECT_NE(unknown.error().message.find("unknown operator 'sharpen'"), std::string::npos);
  auto range = gpuprocess::make_step("lee", {"radius=12"});
  ASSERT_FALSE(range);
  EXPECT_NE(range.error().message.find("out of range"), std::string::npos);
  auto no_stats = gpu().run(chain_of({{"linear", {}}}), tile.raster, border, nullptr);
  ASSERT_FALSE(no_stats);
  EXPECT_EQ(no_stats.error().message, "linear: needs the dataset's global statistics");
  const process::GlobalStats stats = sar_stats();
  // Every operator of the catalogue has a GPU implementation (a new one
  // without is refused by run() with "no GPU implementation yet").
  for (const auto& op : process::operator_catalogue()) {
    EXPECT_TRUE(gpuprocess::runs_on_gpu(op.name)) << op.name;
  }
  auto no_border = gpu().run(chain_of({{"linear", {}}}), tile.raster, 0, &stats);
  ASSERT_FALSE(no_border);
  EXPECT_NE(no_border.error().message.find("border"), std::string::npos);
}

// Two horizontally adjacent tiles processed separately agree where the one
// kept border sample of each overlaps the other's interior.
TEST(GpuChain, ProcessedNeighboursAgreeOnTheKeptBorder) {
  const tiles::Store& store = sar_store();
  const int border = store.manifest().border, level = store.manifest().max_level;
  const process::GlobalStats stats = sar_stats();
  const OperatorChain chain = chain_of({{"lee", {"radius=3"}}, {"ext-schlick", {"max_radius=4"}}});
  int pairs = 0;
  for (const auto& e : store.index(level).entries()) {
    geo::TileKey right = e.key;
    right.x += 1;
    if (!store.has_tile(right) || pairs == 2) continue;
    const tiles::Tile a = must_read(store, e.key), b = must_read(store, right);
    auto pa = gpu().run(chain, a.raster, border, &stats);
    auto pb = gpu().run(chain, b.raster, border, &stats);
    ASSERT_TRUE(pa && pb);
    const int iw = a.header.interior_width();
    int valid = 0;
    for (int y = 0; y < pa->height(); ++y) {
      // a's right border column is b's first interior column, and b's left
      // border column is a's last interior column.
      const float a_border = pa->f32()[y * pa->width() + iw + 1];
      const float b_first = pb->f32()[y * pb->width() + 1];
      const float b_border = pb->f32()[y * pb->width()];
      const float a_last = pa->f32()[y * pa->width() + iw];
      if (std::isnan(a_border) && std::isnan(b_first)) continue;
      ASSERT_EQ(a_border, b_first) << e.key.to_string() << " row " << y;
      ASSERT_EQ(b_border, a_last) << e.key.to_string() << " row " << y;
      ++valid;
    }
    EXPECT_GT(valid, 0);
    ++pairs;
  }
  EXPECT_EQ(pairs, 2);
}

}  // namespace
}  // namespace relief::testing
