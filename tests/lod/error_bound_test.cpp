// The screen-space error bound on real terrain (the Pyrenees): finest samples
// projected from the LOD mesh and from the full-resolution data land within
// the pixel-error threshold of each other. The LOD mesh is evaluated here from
// scratch, as the vertex shader builds it (parent data on coarser sides and
// corners, split border triangles), independently of the error estimate.
#include <gtest/gtest.h>

#include <map>
#include <random>
#include <unordered_map>

#include "../ingest/built_stores.h"
#include "relief/lod/selection.h"

namespace relief::lod {
namespace {

struct Evaluator {
  TerrainModel& terrain;
  std::unordered_map<geo::TileKey, SelectedQuad, geo::TileKeyHash> quads;

  const SelectedQuad* containing(int level, double lon, double lat) const {
    for (int l = terrain.max_level(); l >= 0; --l) {
      const double n = std::ldexp(1.0, l);
      const geo::TileKey k{l, static_cast<uint32_t>((lon + 180) / 360 * n),
                           static_cast<uint32_t>((90 - lat) / 180 * n)};
      if (auto it = quads.find(k); it != quads.end()) return &it->second;
    }
    (void)level;
    return nullptr;
  }

  // Height of mesh vertex v of quad q, as the vertex shader computes it.
  double vertex_height(const SelectedQuad& q, const MeshVertex& v) {
    const bool parent = (v.sides & q.coarse_sides) || (v.corner & q.coarse_corners);
    const DataWindow w = parent ? terrain.parent_window(q.key) : terrain.window(q.key);
    if (!w.tile) return 0;
    auto t = terrain.tile(*w.tile);
    return TerrainModel::bilinear(**t, terrain.border(), w.x0 + v.u * w.width,
                                  w.y0 + v.v * w.height);
  }

  // The mesh point above (lon, lat): the triangle's three vertices placed on
  // the ellipsoid with their heights, interpolated in 3-D.
  Vec3 mesh_point(const SelectedQuad& q, double lon, double lat) {
    const MeshTopology& m = terrain.mesh();
    const geo::GeoBox b = q.key.bounds();
    const double u = (lon - b.west) / b.width(), v = (b.north - lat) / b.height();
    const uint32_t first = m.first_index(q.finer_sides), count = m.index_count(q.finer_sides);
    for (uint32_t t = first; t < first + count; t += 3) {
      const MeshVertex* p[3];
      for (int k = 0; k < 3; ++k) p[k] = &m.vertices()[m.indices()[t + k]];
      const double d =
          (p[1]->u - p[0]->u) * (p[2]->v - p[0]->v) - (p[2]->u - p[0]->u) * (p[1]->v - p[0]->v);
      const double s =
          ((u - p[0]->u) * (p[2]->v - p[0]->v) - (p[2]->u - p[0]->u) * (v - p[0]->v)) / d;
      const double r =
          ((p[1]->u - p[0]->u) * (v - p[0]->v) - (u - p[0]->u) * (p[1]->v - p[0]->v)) / d;
      if (s < -1e-12 || r < -1e-12 || s + r > 1 + 1e-12) continue;
      Vec3 out;
      const double w[3] = {1 - s - r, s, r};
      for (int k = 0; k < 3; ++k) {
        const double plon = b.west + p[k]->u * b.width(), plat = b.north - p[k]->v * b.height();
        out = out + ecef(plon, plat, vertex_height(q, *p[k])) * w[k];
      }
      return out;
    }
    ADD_FAILURE() << "no triangle contains the point";
    return {};
  }
};

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
    Evaluator eval{terrain, {}};
    for (const auto& q : selection->quads) eval.quads[q.key] = q;
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
      const SelectedQuad* q = eval.containing(finest, lon, lat);
      if (!q) continue;  // culled: not on screen
      double ax, ay, bx, by;
      if (!view->project(ecef(lon, lat, h), ax, ay) ||
          !view->project(eval.mesh_point(*q, lon, lat), bx, by))
        continue;
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
    Evaluator eval{terrain, {}};
    std::map<std::pair<double, double>, std::pair<double, geo::TileKey>> seen;
    size_t shared = 0, across_levels = 0;
    for (const auto& q : selection->quads) {
      const geo::GeoBox b = q.key.bounds();
      for (const MeshVertex& v : mesh.vertices()) {
        if (!v.sides) continue;
        const std::pair<double, double> at{b.west + v.u * b.width(), b.north - v.v * b.height()};
        const double h = eval.vertex_height(q, v);
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
