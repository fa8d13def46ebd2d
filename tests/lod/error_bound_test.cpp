// The screen-space error bound on real terrain (the Pyrenees): finest samples
// projected from the LOD mesh and from the full-resolution data land within
// the pixel-error threshold of each other. The LOD mesh is evaluated from
// scratch (lod::MeshEvaluator), as the vertex shader builds it (parent data
// on coarser sides and corners, split border triangles), independently of the
// error estimate.
#include <gtest/gtest.h>

#include <map>
#include <random>
#include <unordered_map>

#include "../ingest/built_stores.h"
#include "relief/lod/mesh_evaluator.h"

namespace relief::lod {
namespace {

TEST(ErrorBound, ProjectedSamplesStayWithinThePixelError) {
  const tiles::Store& store = relief::testing::pyrenees_store();
  const MeshTopology mesh(4);
  TerrainModel terrain(&store, mesh, uint64_t{256} << 20);
  const int finest = store.manifest().max_level;
  const auto& finest_tiles = store.index(finest).entries();
  struct Case {
    Camera camera;
    double pixel_error;
  };
  const Case cases[] = {
      {look_at(1.45, 42.55, 1500, 30000, 20, -35, 60, 640, 480), 1.0},
      {look_at(1.6, 42.4, 1200, 15000, 200, -15, 60, 640, 480), 1.0},
      {look_at(1.5, 42.6, 2000, 60000, 0, -80, 45, 512, 512), 2.0},
  };
  for (const Case& c : cases) {
    auto view = make_view(c.camera);
    ASSERT_TRUE(view);
    SelectionOptions o;
    o.pixel_error = c.pixel_error;
    auto selection = select_quads(*view, terrain, o);
    ASSERT_TRUE(selection) << selection.error().message;
    EXPECT_LE(selection->stats.max_error_pixels, c.pixel_error);
    MeshEvaluator eval(terrain, *selection);
    std::mt19937 rng(5);
    size_t compared = 0;
    double worst = 0;
    for (int n = 0; n < 6000; ++n) {
      const auto& e = finest_tiles[rng() % finest_tiles.size()];
      auto tile = terrain.tile(e.key);
      ASSERT_TRUE(tile);
      const int i = static_cast<int>(rng() % terrain.tile_width()),
                j = static_cast<int>(rng() % terrain.tile_height());
      const double lon = store.grid().sample_lon(e.key, i), lat = store.grid().sample_lat(e.key, j);
      const float h = (*tile)->f32()[static_cast<size_t>(j + terrain.border()) * (*tile)->width() +
                                     i + terrain.border()];
      const SelectedQuad* q = eval.containing(lon, lat);
      if (!q) continue;  // culled: not on screen
      auto on_mesh = eval.mesh_point(*q, lon, lat);
      ASSERT_TRUE(on_mesh) << on_mesh.error().message;
      double ax, ay, bx, by;
      if (!view->project(ecef(lon, lat, h), ax, ay) || !view->project(*on_mesh, bx, by)) continue;
      if (ax < 0 || ay < 0 || ax >= view->width || ay >= view->height) continue;
      worst = std::max(worst, std::hypot(ax - bx, ay - by));
      ++compared;
    }
    EXPECT_GT(compared, 500u);
    EXPECT_LE(worst, c.pixel_error) << "worst " << worst << " px over " << compared << " samples";
  }
}

// No cracks by construction: a vertex shared by quads of different levels
// gets the same height from each of them (both take the coarser level's data,
// whose tiles agree on their shared edges through the overlap borders).
TEST(ErrorBound, SharedVerticesGetIdenticalHeightsFromEveryQuad) {
  const tiles::Store& store = relief::testing::pyrenees_store();
  const MeshTopology mesh(3);
  TerrainModel terrain(&store, mesh, uint64_t{256} << 20);
  const Camera cameras[] = {look_at(1.5, 42.5, 1500, 60000, 120, -70, 60, 480, 360),
                            look_at(1.4, 42.6, 1500, 45000, 200, -35, 60, 480, 360)};
  for (const Camera& c : cameras) {
    auto view = make_view(c);
    ASSERT_TRUE(view);
    SelectionOptions o;
    o.pixel_error = 8;
    auto selection = select_quads(*view, terrain, o);
    ASSERT_TRUE(selection);
    MeshEvaluator eval(terrain, Selection{});
    std::map<std::pair<double, double>, std::pair<double, geo::TileKey>> seen;
    size_t shared = 0, across_levels = 0;
    for (const auto& q : selection->quads) {
      const geo::GeoBox b = q.key.bounds();
      for (const MeshVertex& v : mesh.vertices()) {
        if (!v.sides) continue;
        const std::pair<double, double> at{b.west + v.u * b.width(), b.north - v.v * b.height()};
        const auto height = eval.vertex_height(q, v);
        ASSERT_TRUE(height) << height.error().message;
        const double h = *height;
        auto [it, fresh] = seen.try_emplace(at, h, q.key);
        if (fresh) continue;
        ++shared;
        across_levels += it->second.second.level != q.key.level;
        ASSERT_EQ(it->second.first, h)
            << q.key.to_string() << " and " << it->second.second.to_string() << " at " << at.first
            << "," << at.second;
      }
    }
    EXPECT_GT(shared, 1000u);
    EXPECT_GT(across_levels, 50u);
  }
}

}  // namespace
}  // namespace relief::lod
