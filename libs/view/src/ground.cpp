// The ground under the viewer: the finest resident elevation tile at a point
// (bilinear, as the renderer draws the finest data), and picking by marching
// a pixel's ray against it.
#include "relief/view/ground.h"

#include <algorithm>
#include <cmath>

#include "controls/geometry.h"
#include "relief/geo/ellipsoid.h"
#include "relief/view/scene.h"

namespace relief::view {

namespace {

// The ray of a pixel marches in steps of half the height above the ground
// (never shorter than this, nor than this fraction of the distance), then
// bisects the step that went below.
constexpr double kMinStep = 0.5;             // metres
constexpr double kMinStepOfDistance = 2e-3;  // of the distance from the eye
constexpr int kMaxSteps = 20000;
// Above the highest terrain, a ray going up meets nothing more.
constexpr double kAboveTerrain = 9000;  // metres

// The resident tile of `key`, held only for the query: never waits, never
// requests (what the view needs is the selection's business), never counts
// as a cache miss.
lod::TilePtr resident_tile(Scene& scene, const geo::TileKey& key) {
  stream::TileLoader* loader = scene.elevation_loader();
  if (!loader) {  // complete frames: the blocking model's cache, as their frames read it
    auto t = scene.terrain().tile(key);
    return t ? *t : nullptr;
  }
  if (loader->state(key) != stream::TileState::Resident) return nullptr;
  auto t = loader->get(key);
  return t ? *t : nullptr;
}

}  // namespace

Ground resident_ground(Scene& scene) {
  return [&scene](double lon, double lat) -> std::optional<double> {
    lod::TerrainModel& terrain = scene.terrain();
    const tiles::Store* store = terrain.store();
    if (!store) return 0.0;
    lon = std::remainder(lon, 360.0);
    if (lon >= 180) lon -= 360;
    lat = std::clamp(lat, -90.0, 90.0);
    bool covered = false;
    for (int level = terrain.data_max_level(); level >= 0; --level) {
      const geo::TileKey key = store->grid().locate(level, lon, lat).tile;
      if (!store->has_tile(key)) continue;
      covered = true;
      const lod::TilePtr tile = resident_tile(scene, key);
      if (!tile) continue;
      double fi = 0, fj = 0;
      store->grid().to_sample_coords(key, lon, lat, fi, fj);
      // As drawn: the renderer lifts heights by the exaggeration.
      return double{scene.options().render.exaggeration} *
             lod::TerrainModel::bilinear(*tile, terrain.border(), fi + 0.5, fj + 0.5);
    }
    // No tile of the store: the model draws the ellipsoid there.
    return covered ? std::nullopt : std::optional<double>(0.0);
  };
}

std::optional<Pick> pick(const lod::Camera& camera, double x, double y, const Ground& ground) {
  const auto view = lod::make_view(camera);
  if (!view) return std::nullopt;
  const double nx = 2 * x / camera.width - 1, ny = 1 - 2 * y / camera.height_px;
  const lod::Vec3 ray = lod::normalize(view->forward + view->right * (nx * view->tan_half_x) +
                                       view->up * (ny * view->tan_half_y));
  geo::Geodetic g;
  auto above = [&](double t) {
    const lod::Vec3 p = view->eye + ray * t;
    g = geo::to_geodetic({p.x, p.y, p.z});
    return g.height_m - controls::ground_or_zero(ground, g.lon_deg, g.lat_deg);
  };
  auto at = [&](double t) {
    above(t);
    return Pick{g.lon_deg, g.lat_deg, g.height_m, t};
  };
  double t = 0, h = above(0);
  if (h <= 0) return at(0);  // the eye is in the ground
  for (int i = 0; i < kMaxSteps; ++i) {
    if (g.height_m > kAboveTerrain && lod::dot(ray, lod::up_at(g.lon_deg, g.lat_deg)) >= 0) {
      return std::nullopt;  // sky
    }
    const double next = t + std::max({0.5 * h, kMinStep, kMinStepOfDistance * t});
    const double h_next = above(next);
    if (h_next <= 0) {
      double lo = t, hi = next;
      for (int b = 0; b < 80 && hi - lo > 1e-7 * (1 + lo); ++b) {
        const double mid = 0.5 * (lo + hi);
        (above(mid) > 0 ? lo : hi) = mid;
      }
      return at(0.5 * (lo + hi));
    }
    t = next;
    h = h_next;
  }
  return std::nullopt;
}

}  // namespace relief::view
