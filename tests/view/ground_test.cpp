// The ground under the viewer over the real Pyrenees store: the finest
// resident tile's heights without waiting or requesting anything, and
// picking the terrain point of a pixel.
#include <cmath>

#include "controls_input.h"
#include "loaded_scene.h"
#include "relief/geo/ellipsoid.h"
#include "relief/lod/terrain_model.h"
#include "relief/view/ground.h"

namespace relief::view {
namespace {

class GroundTest : public testing::LoadedSceneTest {};

const lod::Camera kView = lod::look_at(1.5, 42.6, 1500, 12000, 20, -30, 60, 160, 120);

TEST_F(GroundTest, AFreshSceneHasLevelZeroAndNeverRequestsOrWaits) {
  const Ground ground = resident_ground(*scene_);
  const stream::LoaderStats before = scene_->elevation_loader()->stats();
  const tiles::Store& store = relief::testing::pyrenees_store();
  const geo::TileKey root = store.grid().locate(0, 1.5, 42.6).tile;
  tiles::Tile tile = relief::testing::must_read(store, root);
  double fi = 0, fj = 0;
  store.grid().to_sample_coords(root, 1.5, 42.6, fi, fj);
  const auto h = ground(1.5, 42.6);
  ASSERT_TRUE(h);
  EXPECT_EQ(*h,
            lod::TerrainModel::bilinear(tile.raster, store.grid().border(), fi + 0.5, fj + 0.5));
  const stream::LoaderStats after = scene_->elevation_loader()->stats();
  EXPECT_EQ(after.requested, before.requested);
  EXPECT_EQ(after.misses, before.misses);
  EXPECT_EQ(after.pinned_bytes, before.pinned_bytes);
}

TEST_F(GroundTest, AfterLoadingItIsTheFinestTileAtItsSamples) {
  load(kView);
  const Ground ground = resident_ground(*scene_);
  const tiles::Store& store = relief::testing::pyrenees_store();
  const geo::TileGrid& grid = store.grid();
  const int finest = scene_->terrain().data_max_level();
  int at_finest = 0;
  for (int k = 0; k < 40; ++k) {
    // Sample centres of the finest level near the view's target, where a
    // bilinear height is the sample itself.
    const geo::SampleIndex s = grid.locate(finest, 1.5 + 0.001 * (k % 7), 42.6 + 0.0013 * (k / 7));
    if (scene_->elevation_loader()->state(s.tile) != stream::TileState::Resident) continue;
    ++at_finest;
    const double lon = grid.sample_lon(s.tile, s.i), lat = grid.sample_lat(s.tile, s.j);
    const tiles::Tile tile = relief::testing::must_read(store, s.tile);
    const int w = tile.raster.width(), b = grid.border();
    float expected = tile.raster.f32()[static_cast<size_t>(s.j + b) * w + (s.i + b)];
    if (std::isnan(expected)) expected = 0;
    const auto h = ground(lon, lat);
    ASSERT_TRUE(h);
    EXPECT_NEAR(*h, expected, 1e-3) << lon << " " << lat;
  }
  EXPECT_GT(at_finest, 20);
  // Outside the data: the ellipsoid, as drawn.
  EXPECT_EQ(ground(100, 0), 0.0);
  // Exaggerated heights, as drawn.
  const double h = *ground(1.5, 42.6);
  render::RenderOptions exaggerated = scene_->options().render;
  exaggerated.exaggeration = 2.5f;
  scene_->set_render_options(exaggerated);
  EXPECT_DOUBLE_EQ(*ground(1.5, 42.6), 2.5 * h);
}

TEST_F(GroundTest, APickIsTheFirstGroundPointAlongThePixelsRay) {
  load(kView);
  const Ground ground = resident_ground(*scene_);
  auto view = lod::make_view(kView);
  ASSERT_TRUE(view);
  int hits = 0;
  for (double y = 0.5; y < 120; y += 17) {
    for (double x = 0.5; x < 160; x += 23) {
      const auto p = pick(kView, x, y, ground);
      if (!p) continue;
      ++hits;
      const lod::Vec3 point = lod::ecef(p->lon, p->lat, p->height);
      double sx = 0, sy = 0;
      ASSERT_TRUE(view->project(point, sx, sy));
      EXPECT_NEAR(sx, x, 1e-3);
      EXPECT_NEAR(sy, y, 1e-3);
      EXPECT_NEAR(p->height, *ground(p->lon, p->lat), 0.01);
      EXPECT_NEAR(lod::length(point - view->eye), p->distance, 1e-6 * p->distance);
      // Nothing of the ground nearer along the ray.
      for (int i = 1; i < 400; ++i) {
        const lod::Vec3 q = view->eye + (point - view->eye) * (i / 400.0 * 0.999);
        const geo::Geodetic g = geo::to_geodetic({q.x, q.y, q.z});
        ASSERT_GT(g.height_m, *ground(g.lon_deg, g.lat_deg)) << x << "," << y << " at " << i;
      }
    }
  }
  EXPECT_GT(hits, 30);
  // Looking up at the horizon: the sky has no point.
  lod::Camera up = kView;
  up.pitch = 20;
  EXPECT_FALSE(pick(up, 80, 0.5, ground));
}

TEST_F(GroundTest, OrbitZoomKeepsTheTerrainPointUnderTheCursor) {
  load(kView);
  const Ground ground = resident_ground(*scene_);
  auto orbit = make_controller(ControlMode::orbit, kView);
  const auto p = pick(kView, 120, 90, ground);
  ASSERT_TRUE(p);
  const lod::Vec3 point = lod::ecef(p->lon, p->lat, p->height);
  orbit->push(view::testing::cursor(120, 90));
  for (int i = 0; i < 8; ++i) {
    orbit->push(view::testing::scroll(1));
    auto view = lod::make_view(orbit->update(1.0 / 60, ground));
    ASSERT_TRUE(view);
    double sx = 0, sy = 0;
    ASSERT_TRUE(view->project(point, sx, sy));
    EXPECT_NEAR(sx, 120, 1e-6);
    EXPECT_NEAR(sy, 90, 1e-6);
    EXPECT_NEAR(lod::length(view->eye - point), p->distance * std::pow(0.8, i + 1),
                1e-6 * p->distance);
  }
}

}  // namespace
}  // namespace relief::view
