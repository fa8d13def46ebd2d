// Elevation processed at draw time (pipeline/processed_elevation.h): N41E001
// and N42E001 fused as two layers, smoothed by a chain, with a lens that
// shows the unsmoothed heights inside a circle in the Andorran mountains. The guarantee
// holds over the processed heights, brute force (layer_guarantee.h: every
// finest processed sample within the threshold of the drawn mesh, 1 and 2 px,
// edge marks and quads), and quads on both sides of the lens's circle give
// shared vertices bit-identical heights: no crack where the chains meet.
#include <gtest/gtest.h>

#include <cmath>
#include <map>

#include "../ingest/built_stores.h"
#include "../support/test_support.h"
#include "layer_guarantee.h"
#include "relief/lod/mesh_evaluator.h"
#include "relief/pipeline/fused_elevation.h"
#include "relief/pipeline/processed_elevation.h"

namespace relief::lod {
namespace {

constexpr double kLensLon = 1.55, kLensLat = 42.55, kLensRadius = 3000;

const tiles::Store& layer(const std::string& name, const std::string& file) {
  ingest::BuildOptions o;
  o.inputs = {relief::testing::data(file)};
  o.kind = tiles::DatasetKind::Elevation;
  return relief::testing::built_store(name, o);
}

tiles::Store make_processed() {
  std::vector<pipeline::ElevationLayer> layers;
  layers.push_back({"n41", layer("n41", "srtm/N41E001.hgt.zip")});
  layers.push_back({"n42", layer("n42", "srtm/N42E001.hgt.zip")});
  ThreadExecutor executor;
  auto fused =
      pipeline::fuse_elevation_layers(std::move(layers), pipeline::FuseMode::First, executor);
  if (!fused) throw std::runtime_error(fused.error().message);
  pipeline::ElevationProcessing p;
  p.chain.steps.push_back(*gpuprocess::make_step("median", {"radius=2"}));
  p.chain.steps.push_back(*gpuprocess::make_step("mean", {"radius=5"}));
  p.lenses.push_back({kLensLon, kLensLat, kLensRadius, {}});  // the fused heights as they are
  auto store = pipeline::process_elevation(std::move(*fused), "n41+n42", std::move(p), executor);
  if (!store) throw std::runtime_error(store.error().message);
  return std::move(*store);
}

const tiles::Store& processed() {
  static const tiles::Store s = make_processed();
  return s;
}

// Views across 42N, and across the lens's circle.
const GuaranteeCase kCases[] = {
    {look_at(1.5, 42.0, 1000, 30000, 10, -35, 60, 640, 480), 1.0},
    {look_at(1.3, 41.95, 800, 15000, 170, -15, 60, 640, 480), 1.0},
    {look_at(1.5, 42.0, 1000, 60000, 0, -80, 45, 512, 512), 2.0},
    {look_at(kLensLon, kLensLat, 2000, 12000, 30, -40, 60, 640, 480), 1.0},
};

TEST(ProcessedLayers, QuadMeshesKeepTheGuaranteeOverProcessedHeights) {
  expect_quads_keep_the_guarantee(processed(), kCases);
}

TEST(ProcessedLayers, RefinedMeshesKeepTheGuaranteeOverProcessedHeights) {
  expect_refined_meshes_keep_the_guarantee(processed(), kCases);
}

// Where the lens's circle crosses quads of equal and different levels, every
// vertex on a quad's side gets the same height from each quad that has it.
TEST(ProcessedLayers, SharedVerticesAcrossTheLensBorderAreBitIdentical) {
  const tiles::Store& store = processed();
  const MeshTopology mesh(3);
  TerrainModel terrain(&store, mesh, uint64_t{256} << 20);
  const Camera cameras[] = {look_at(kLensLon, kLensLat, 2000, 20000, 30, -60, 60, 480, 360),
                            look_at(kLensLon, kLensLat, 2000, 12000, 220, -30, 60, 480, 360)};
  for (const Camera& c : cameras) {
    auto view = make_view(c);
    ASSERT_TRUE(view);
    SelectionOptions o;
    o.pixel_error = 2;
    o.mode = LodMode::quads;
    auto selection = select_quads(*view, terrain, o);
    ASSERT_TRUE(selection) << selection.error().message;
    MeshEvaluator eval(terrain, Selection{});
    std::map<std::pair<double, double>, std::pair<double, geo::TileKey>> seen;
    size_t shared = 0, across_levels = 0, on_the_circle = 0;
    for (const auto& q : selection->quads) {
      const geo::GeoBox b = q.key.bounds();
      for (const MeshVertex& v : mesh.vertices()) {
        if (!v.sides) continue;
        const std::pair<double, double> at{b.west + v.u * b.width(), b.north - v.v * b.height()};
        const auto height = eval.vertex_height(q, v);
        ASSERT_TRUE(height) << height.error().message;
        auto [it, fresh] = seen.try_emplace(at, *height, q.key);
        if (fresh) continue;
        ++shared;
        across_levels += it->second.second.level != q.key.level;
        const double d = pipeline::lens_distance_m(kLensLon, kLensLat, at.first, at.second);
        on_the_circle += std::abs(d - kLensRadius) < 300;
        ASSERT_EQ(it->second.first, *height)
            << q.key.to_string() << " and " << it->second.second.to_string() << " at " << at.first
            << "," << at.second;
      }
    }
    EXPECT_GT(shared, 1000u);
    EXPECT_GT(across_levels, 20u);
    EXPECT_GT(on_the_circle, 20u);
  }
}

}  // namespace
}  // namespace relief::lod
