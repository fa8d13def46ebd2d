#include "gpu_fixture.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <functional>
#include <limits>
#include <map>
#include <memory>

#include "../ingest/built_stores.h"
#include "../support/test_support.h"
#include "relief/render/render_target.h"

namespace relief::testing {

gpuprocess::GpuProcessor& gpu() {
  // Created once, on the test thread, which owns the context to the end.
  static auto context = [] {
    auto c = render::GlContext::create_headless();
    if (!c) throw std::runtime_error(c.error().message);
    return std::move(*c);
  }();
  static auto processor = [] {
    auto p = gpuprocess::GpuProcessor::create();
    if (!p) throw std::runtime_error(p.error().message);
    return std::move(*p);
  }();
  (void)context;
  return *processor;
}

const tiles::Store& sar_store() {
  ingest::BuildOptions o;
  o.inputs = {data("sar/umbra_mount_yasur.tif")};
  o.kind = tiles::DatasetKind::Sar;
  return built_store("umbra", o);
}

process::GlobalStats sar_stats() {
  const auto& s = sar_store().manifest().stats;
  return {s.min, s.max, s.mean, s.stddev};
}

gpuprocess::OperatorChain chain_of(
    const std::vector<std::pair<std::string, std::vector<std::string>>>& steps) {
  gpuprocess::OperatorChain chain;
  for (const auto& [op, params] : steps) {
    auto step = gpuprocess::make_step(op, params);
    if (!step) throw std::runtime_error(step.error().message);
    chain.steps.push_back(*step);
  }
  return chain;
}

double max_relative_error(const tiles::Raster& gpu, const tiles::Raster& cpu) {
  constexpr double kInf = std::numeric_limits<double>::infinity();
  if (gpu.width() != cpu.width() || gpu.height() != cpu.height()) return kInf;
  double worst = 0;
  const auto g = gpu.f32(), c = cpu.f32();
  for (size_t i = 0; i < g.size(); ++i) {
    if (g[i] == c[i]) continue;  // infinities included
    if (std::isnan(g[i]) || std::isnan(c[i]) || std::isinf(g[i]) || std::isinf(c[i])) {
      if (!(std::isnan(g[i]) && std::isnan(c[i]))) return kInf;
      continue;
    }
    const double d = std::abs(static_cast<double>(g[i]) - c[i]);
    worst = std::max(worst, d / std::abs(static_cast<double>(c[i])));
  }
  return worst;
}

namespace {

// The level's tiles, those with the most valid samples first (the image's
// edges give nodata too); computed once per level.
const std::vector<geo::TileKey>& fullest_tiles(int level) {
  static std::map<int, std::vector<geo::TileKey>> cache;
  if (auto it = cache.find(level); it != cache.end()) return it->second;
  std::vector<std::pair<uint64_t, geo::TileKey>> counted;
  for (const auto& e : sar_store().index(level).entries()) {
    const tiles::Tile t = must_read(sar_store(), e.key);
    counted.emplace_back(t.raster.stats(0, 0, t.raster.width(), t.raster.height()).valid_count,
                         e.key);
  }
  std::ranges::stable_sort(counted, std::greater<>(), [](const auto& c) { return c.first; });
  std::vector<geo::TileKey> keys;
  for (const auto& c : counted) keys.push_back(c.second);
  return cache.emplace(level, std::move(keys)).first->second;
}

}  // namespace

double expect_gpu_equals_cpu(const gpuprocess::OperatorChain& chain, double tolerance, int tiles) {
  const tiles::Store& store = sar_store();
  const process::GlobalStats stats = sar_stats();
  const int max = store.manifest().max_level, border = store.manifest().border;
  InlineExecutor ex;
  double worst = 0;
  int compared = 0;
  for (int level : {max, max - 1, max - 2}) {
    const auto scaled = gpuprocess::scale_chain(chain, std::ldexp(1.0, max - level));
    const std::vector<geo::TileKey>& keys = fullest_tiles(level);
    for (size_t i = 0; i < keys.size() && i < static_cast<size_t>(tiles); ++i) {
      const tiles::Tile tile = must_read(store, keys[i]);
      const std::string key = keys[i].to_string();
      auto cpu = gpuprocess::run_chain_cpu(scaled, tile.raster, border, &stats, ex);
      auto got = gpu().run(scaled, tile.raster, border, &stats);
      EXPECT_TRUE(cpu) << cpu.error().message;
      EXPECT_TRUE(got) << got.error().message;
      if (!cpu || !got) return worst;
      const double e = max_relative_error(*got, *cpu);
      EXPECT_LE(e, tolerance) << key;
      const tiles::SampleStats st = got->stats(0, 0, got->width(), got->height());
      EXPECT_GT(st.valid_count, 1000u) << key;
      EXPECT_LT(st.min, st.max) << key << ": a constant result compares too easily";
      worst = std::max(worst, e);
      ++compared;
    }
  }
  EXPECT_GE(compared, 3);
  return worst;
}

}  // namespace relief::testing
