// A single-band store coloured for the web (pipeline::colour_layer): an
// imagery store of the same tiles, each sample the grey level of its value in
// the range (checked against the formula on the SAR store's own samples),
// transparent where there is no data; a chain changes the tiles; unsuitable
// stores, chains and ranges are one-line errors naming the store.
#include <gtest/gtest.h>

#include <cmath>

#include "../ingest/built_stores.h"
#include "../support/test_support.h"
#include "relief/pipeline/coloured_layer.h"

namespace relief::testing {
namespace {

const tiles::Store& umbra() {
  ingest::BuildOptions o;
  o.inputs = {data("sar/umbra_mount_yasur.tif")};
  o.kind = tiles::DatasetKind::Sar;
  return built_store("umbra-coloured", o);
}

gpuprocess::OperatorChain chain_of(const std::string& op, std::vector<std::string> params = {}) {
  gpuprocess::OperatorChain c;
  auto step = gpuprocess::make_step(op, params);
  EXPECT_TRUE(step) << step.error().message;
  c.steps.push_back(std::move(*step));
  return c;
}

TEST(ColouredLayer, GreyLevelsOfTheValuesInTheRangeAndTransparentNodata) {
  const tiles::Store& sar = umbra();
  const float lo = 20, hi = 180;
  auto coloured = pipeline::colour_layer(sar, "umbra", {{}, lo, hi, gpuprocess::ColorMap::grey});
  ASSERT_TRUE(coloured) << coloured.error().message;
  EXPECT_EQ(coloured->manifest().kind, tiles::DatasetKind::Imagery);
  EXPECT_EQ(coloured->manifest().bands, 4);
  const int level = sar.manifest().max_level;
  ASSERT_EQ(coloured->index(level).entries().size(), sar.index(level).entries().size());
  int opaque = 0, transparent = 0;
  for (const tiles::IndexEntry& e : sar.index(level).entries()) {
    auto in = sar.read_tile(e.key);
    auto out = coloured->read_tile(e.key);
    ASSERT_TRUE(in && out) << e.key.to_string();
    const int bi = sar.grid().border(), bo = coloured->manifest().border;
    const int wi = in->raster.width(), wo = out->raster.width();
    for (int y = 0; y < sar.grid().height(); y += 7) {
      for (int x = 0; x < sar.grid().width(); x += 5) {
        const float v = in->raster.f32()[static_cast<size_t>(y + bi) * wi + x + bi];
        const auto px =
            out->raster.u8().subspan((static_cast<size_t>(y + bo) * wo + x + bo) * 4, 4);
        if (std::isnan(v)) {
          EXPECT_EQ(px[3], 0) << e.key.to_string() << " " << x << "," << y;
          ++transparent;
          continue;
        }
        const double grey = 255.0 * std::clamp((v - lo) / (hi - lo), 0.0f, 1.0f);
        EXPECT_EQ(px[3], 255);
        EXPECT_NEAR(px[0], grey, 1.0) << e.key.to_string() << " " << x << "," << y << " v " << v;
        EXPECT_EQ(px[0], px[1]);
        EXPECT_EQ(px[1], px[2]);
        ++opaque;
      }
    }
  }
  EXPECT_GT(opaque, 1000);
  EXPECT_GT(transparent, 0);  // the image does not fill its tiles

  // A speckle filter and a dynamic-range mapping: other colours, same tiles.
  gpuprocess::OperatorChain lee_log = chain_of("lee");
  lee_log.steps.push_back(chain_of("log").steps.front());
  auto filtered =
      pipeline::colour_layer(sar, "umbra", {lee_log, 0, 1, gpuprocess::ColorMap::viridis});
  ASSERT_TRUE(filtered) << filtered.error().message;
  geo::TileKey key;  // the tile with the most data
  uint32_t most = 0;
  for (const tiles::IndexEntry& e : sar.index(level).entries()) {
    if (e.valid_count > most) most = e.valid_count, key = e.key;
  }
  ASSERT_GT(most, 0u);
  bool differs = false;
  const auto filtered_tile = filtered->read_tile(key), plain_tile = coloured->read_tile(key);
  ASSERT_TRUE(filtered_tile && plain_tile);
  const auto a = filtered_tile->raster.u8(), b = plain_tile->raster.u8();
  for (size_t i = 0; i < a.size() && !differs; ++i) differs = a[i] != b[i];
  EXPECT_TRUE(differs);
}

TEST(ColouredLayer, UnsuitableInputsAreOneLineErrorsNamingTheStore) {
  const tiles::Store& sar = umbra();
  auto empty = pipeline::colour_layer(sar, "umbra", {{}, 5, 5, gpuprocess::ColorMap::grey});
  ASSERT_FALSE(empty);
  EXPECT_TRUE(empty.error().message.starts_with("umbra: ")) << empty.error().message;
  EXPECT_NE(empty.error().message.find("range"), std::string::npos);
  auto wide = pipeline::colour_layer(
      sar, "umbra", {chain_of("mean", {"radius=9"}), 0, 1, gpuprocess::ColorMap::grey});
  ASSERT_FALSE(wide);
  EXPECT_TRUE(wide.error().message.starts_with("umbra")) << wide.error().message;
  EXPECT_EQ(wide.error().message.find('\n'), std::string::npos);

  ingest::BuildOptions o;
  o.inputs = {data("imagery/RGB.byte.tif")};
  o.kind = tiles::DatasetKind::Imagery;
  auto rgba = pipeline::colour_layer(built_store("rgb-coloured", o), "rgb",
                                     {{}, 0, 1, gpuprocess::ColorMap::grey});
  ASSERT_FALSE(rgba);
  EXPECT_NE(rgba.error().message.find("single-band"), std::string::npos) << rgba.error().message;
}

}  // namespace
}  // namespace relief::testing
