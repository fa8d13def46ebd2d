// The full mesh that geometric errors are measured from: sample values at
// cell centres, corner means at cell corners, planes in between.
#include "relief/tiles/full_mesh.h"

#include <gtest/gtest.h>

#include <cmath>
#include <limits>

#include "test_rasters.h"

namespace relief::tiles {
namespace {

constexpr int kBorder = 2;

// A bordered 8 x 4 tile of terrain-like samples, without holes.
Raster tile() {
  return testing::terrain(8 + 2 * kBorder, 4 + 2 * kBorder, 7, false);
}

float sample(const Raster& r, int i, int j) {
  return r.f32()[static_cast<size_t>(j + kBorder) * r.width() + i + kBorder];
}

TEST(FullMesh, VerticesAreSamplesAndCornerMeans) {
  const Raster r = tile();
  for (int j = 0; j < 4; ++j) {
    for (int i = 0; i < 8; ++i) {
      EXPECT_NEAR(full_mesh_height(r, kBorder, i + 0.5, j + 0.5), sample(r, i, j), 1e-9);
      const double mean =
          (sample(r, i - 1, j - 1) + sample(r, i, j - 1) + sample(r, i - 1, j) + sample(r, i, j)) /
          4.0;
      EXPECT_NEAR(full_mesh_height(r, kBorder, i, j), mean, 1e-3);  // float arithmetic
    }
  }
}

TEST(FullMesh, LinearAlongTheDiagonalsAndTheEdges) {
  const Raster r = tile();
  const int i = 3, j = 1;
  const double c = full_mesh_height(r, kBorder, i + 0.5, j + 0.5);
  const double h00 = full_mesh_height(r, kBorder, i, j);
  const double h10 = full_mesh_height(r, kBorder, i + 1, j);
  const double h11 = full_mesh_height(r, kBorder, i + 1, j + 1);
  for (double t : {0.1, 0.25, 0.4}) {
    // From the corner (0,0) towards the centre, and along the cell's top edge.
    EXPECT_NEAR(full_mesh_height(r, kBorder, i + t, j + t), h00 + (c - h00) * 2 * t, 1e-9);
    EXPECT_NEAR(full_mesh_height(r, kBorder, i + 2 * t, j), h00 + (h10 - h00) * 2 * t, 1e-9);
    // The right edge, and the plane of the triangle on it at (1 - t/2, 1/2).
    EXPECT_NEAR(full_mesh_height(r, kBorder, i + 1, j + 2 * t), h10 + (h11 - h10) * 2 * t, 1e-9);
    EXPECT_NEAR(full_mesh_height(r, kBorder, i + 1 - t / 2, j + 0.5),
                (1 - t) * (h10 + h11) / 2 + t * c, 1e-9);
  }
}

TEST(FullMesh, TheStencilIsTheThreeByThreeSamplesAroundTheCell) {
  Raster r = tile();
  EXPECT_TRUE(full_mesh_stencil_valid(r, kBorder, 3.7, 1.2));
  // A hole diagonally next to cell (3, 1) is in its stencil (a corner averages
  // it), one two samples away is not.
  r.f32()[static_cast<size_t>(0 + kBorder) * r.width() + 4 + kBorder] =
      std::numeric_limits<float>::quiet_NaN();  // sample (4, 0)
  EXPECT_FALSE(full_mesh_stencil_valid(r, kBorder, 3.7, 1.2));
  EXPECT_FALSE(full_mesh_stencil_valid(r, kBorder, 3.01, 1.99));
  EXPECT_TRUE(full_mesh_stencil_valid(r, kBorder, 2.5, 2.5));  // cell (2, 2)
  // Without a border, the tile's edge cells reach outside the raster.
  const Raster bare = testing::terrain(8, 4, 7, false);
  EXPECT_FALSE(full_mesh_stencil_valid(bare, 0, 0.5, 1.5));
  EXPECT_TRUE(full_mesh_stencil_valid(bare, 0, 1.5, 1.5));
}

}  // namespace
}  // namespace relief::tiles
