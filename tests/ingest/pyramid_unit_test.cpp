// White-box tests of the pyramid kernels on small synthetic rasters.
#include "pyramid.h"

#include <gtest/gtest.h>

#include <cmath>

namespace relief::ingest {
namespace {

using tiles::Raster;
using tiles::SampleType;

TEST(Downsample, FloatIsNodataAwareMeanPerQuadrant) {
  Raster child = Raster::empty(SampleType::Float32, 4, 2);
  auto v = child.f32();
  // 2 x 2 block (0,0): 1, 2, 3, NaN -> mean 2. Block (1,0): all NaN -> NaN.
  v[0] = 1, v[1] = 2, v[4] = 3;
  const Raster parent = downsample({&child, nullptr, nullptr, &child}, 4, 2, SampleType::Float32);
  const auto p = parent.f32();
  EXPECT_FLOAT_EQ(p[0], 2.0f);      // child (0,0) lands in the top-left quadrant
  EXPECT_TRUE(std::isnan(p[1]));    // its all-nodata block
  EXPECT_TRUE(std::isnan(p[2]));    // child (1,0) is missing
  EXPECT_FLOAT_EQ(p[4 + 2], 2.0f);  // child (1,1) = same raster, bottom-right quadrant
}

TEST(Downsample, RgbaAveragesValidColoursAndCoverage) {
  Raster child(SampleType::UInt8, 4, 2, 2);
  auto px = child.u8();
  const uint8_t pixels[4][4] = {
      {10, 20, 30, 255}, {30, 40, 50, 255}, {0, 0, 0, 0}, {200, 200, 200, 0}};
  for (int k = 0; k < 4; ++k) {
    for (int c = 0; c < 4; ++c) px[k * 4 + c] = pixels[k][c];
  }
  const Raster parent = downsample({&child, nullptr, nullptr, nullptr}, 2, 2, SampleType::UInt8);
  const auto p = parent.u8();
  EXPECT_EQ(p[0], 20);  // mean of the two valid pixels' red, transparent ones ignored
  EXPECT_EQ(p[1], 30);
  EXPECT_EQ(p[2], 40);
  EXPECT_EQ(p[3], 128);  // half covered
  EXPECT_EQ(p[7], 0);    // missing children stay transparent
}

TEST(AssembleBordered, TakesEachBorderFromTheOwningNeighbour) {
  const int w = 4, h = 2, b = 1;
  std::array<Raster, 9> cores;
  std::array<const Raster*, 9> around{};
  for (int k = 0; k < 9; ++k) {
    cores[k] = Raster(SampleType::Float32, 1, w, h);
    for (int s = 0; s < w * h; ++s) cores[k].f32()[s] = static_cast<float>(k * 100 + s);
    around[k] = &cores[k];
  }
  around[0] = nullptr;  // the north-west neighbour does not exist
  const Raster t = tiles::assemble_bordered(around, w, h, b, SampleType::Float32);
  ASSERT_EQ(t.width(), w + 2);
  ASSERT_EQ(t.height(), h + 2);
  auto at = [&](int i, int j) { return t.f32()[(j + b) * (w + 2) + (i + b)]; };
  EXPECT_EQ(at(0, 0), 400.0f);          // interior = centre core
  EXPECT_EQ(at(-1, 0), 300.0f + 3);     // west neighbour's last column
  EXPECT_EQ(at(w, 1), 500.0f + 4);      // east neighbour's first column, row 1
  EXPECT_EQ(at(0, -1), 100.0f + 4);     // north neighbour's last row
  EXPECT_EQ(at(w, h), 800.0f);          // south-east corner
  EXPECT_TRUE(std::isnan(at(-1, -1)));  // missing north-west: nodata
}

}  // namespace
}  // namespace relief::ingest
