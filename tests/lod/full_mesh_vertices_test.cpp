// The full mesh that stores' geometric errors are measured from
// (relief/tiles/full_mesh.h) has the renderer's heights at its vertices, bit
// for bit: the corners are TerrainModel::bilinear's, the centres the samples.
#include <gtest/gtest.h>

#include <random>

#include "relief/lod/terrain_model.h"
#include "relief/tiles/full_mesh.h"

namespace relief::lod {
namespace {

TEST(FullMesh, VerticesAreTheRenderersHeights) {
  const int border = 3, w = 16, h = 8;
  tiles::Raster r(tiles::SampleType::Float32, 1, w + 2 * border, h + 2 * border);
  std::mt19937 rng(5);
  std::uniform_real_distribution<float> height(-400.0f, 8800.0f);
  for (float& v : r.f32()) v = height(rng);
  // Corners and centres of every cell, the edge ones averaging border samples.
  for (int j = 0; j < h; ++j) {
    for (int i = 0; i < w; ++i) {
      EXPECT_EQ(tiles::full_mesh_height(r, border, i, j), TerrainModel::bilinear(r, border, i, j))
          << i << "," << j;
      EXPECT_NEAR(tiles::full_mesh_height(r, border, i + 0.5, j + 0.5),
                  TerrainModel::bilinear(r, border, i + 0.5, j + 0.5), 1e-9);
    }
  }
}

}  // namespace
}  // namespace relief::lod
