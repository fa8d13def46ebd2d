// Edge-mark refinement (lod/refine.h) on real terrain: the Pyrenees pair and
// the Scotland pair (55N, west of Greenwich). The refined mesh is evaluated
// from scratch as the renderer draws it (grid vertex heights from the quad's
// data window, the parent's on sides and corners shared with a coarser quad;
// flat triangles between the vertices placed in ECEF), independently of the
// refinement's error estimates, and compared with every finest sample it
// covers on screen.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <map>
#include <random>
#include <unordered_map>
#include <unordered_set>

#include "../ingest/built_stores.h"
#include "../support/test_support.h"
#include "relief/lod/mesh_evaluator.h"
#include "relief/lod/refine.h"

namespace relief::lod {
namespace {

const tiles::Store& scotland_store() {
  ingest::BuildOptions o;
  o.inputs = {relief::testing::data("srtm/N55W004.hgt.zip"),
              relief::testing::data("srtm/N55W003.hgt.zip")};
  o.kind = tiles::DatasetKind::Elevation;
  return relief::testing::built_store("scotland", o);
}

struct Terrain {
  explicit Terrain(const tiles::Store& s) : store(s), terrain(&s, mesh, uint64_t{512} << 20) {}
  const tiles::Store& store;
  MeshTopology mesh{4};
  TerrainModel terrain;
  RefineCache cache{uint64_t{2} << 30};
};

Terrain& pyrenees() {
  static Terrain t(relief::testing::pyrenees_store());
  return t;
}
Terrain& scotland() {
  static Terrain t(scotland_store());
  return t;
}

// The quad selection refinement starts from: capped at the store's finest level.
Selection select(Terrain& t, const View& view, double pixel_error) {
  SelectionOptions o;
  o.pixel_error = pixel_error;
  o.neighbour_indices = true;
  o.max_level = t.terrain.data_max_level();
  auto s = select_quads(view, t.terrain, o);
  EXPECT_TRUE(s) << s.error().message;
  return s ? std::move(*s) : Selection{};
}

RefinedMesh refined(Terrain& t, const View& view, const Selection& s, double pixel_error,
                    RefineVariant variant) {
  RefineOptions o;
  o.pixel_error = pixel_error;
  o.variant = variant;
  o.cache = &t.cache;
  auto mesh = refine(view, t.terrain, s, o);
  EXPECT_TRUE(mesh) << mesh.error().message;
  return mesh ? std::move(*mesh) : RefinedMesh{};
}

struct GridPos {
  int x = 0, y = 0;
};

// The refined mesh as the renderer draws it.
class RefinedEvaluator {
 public:
  RefinedEvaluator(TerrainModel& terrain, const Selection& s, const RefinedMesh& m)
      : terrain_(terrain), selection_(s), mesh_(m), eval_(terrain, s), n_(1 << m.grid_k) {
    triangles_.resize(s.quads.size());
    for (size_t q = 0; q < s.quads.size(); ++q) {
      index_[s.quads[q].key] = q;
      const RefinedQuad& rq = m.quads[q];
      for (uint32_t i = rq.first_index; i < rq.first_index + rq.index_count; i += 3) {
        triangles_[q].insert(key(m.indices[i], m.indices[i + 1], m.indices[i + 2]));
      }
    }
  }

  GridPos pos(uint32_t id) const {
    const int c = static_cast<int>(mesh_.grid_columns());
    return {static_cast<int>(id) % c, static_cast<int>(id) / c};
  }
  uint32_t id(GridPos p) const { return static_cast<uint32_t>(p.y) * mesh_.grid_columns() + p.x; }

  // Lon/lat of grid point p of quad q (exact: dyadic fractions).
  std::pair<double, double> lonlat(const SelectedQuad& q, GridPos p) const {
    const geo::GeoBox b = q.key.bounds();
    double lon = b.west + p.x / (2.0 * n_) * b.width();
    if (lon >= 180) lon -= 360;
    return {lon, b.north - p.y / double(n_) * b.height()};
  }

  // Height of grid point p of quad q as the vertex shader computes it.
  double height(const SelectedQuad& q, GridPos p) {
    MeshVertex v;
    v.u = static_cast<float>(p.x / (2.0 * n_));
    v.v = static_cast<float>(p.y / double(n_));
    if (p.x == 0) v.sides |= kWest;
    if (p.x == 2 * n_) v.sides |= kEast;
    if (p.y == 0) v.sides |= kNorth;
    if (p.y == n_) v.sides |= kSouth;
    const uint8_t s = v.sides;
    if ((s & kNorth) && (s & kWest)) v.corner = kNorthWest;
    if ((s & kNorth) && (s & kEast)) v.corner = kNorthEast;
    if ((s & kSouth) && (s & kWest)) v.corner = kSouthWest;
    if ((s & kSouth) && (s & kEast)) v.corner = kSouthEast;
    auto h = eval_.vertex_height(q, v);
    EXPECT_TRUE(h);
    return h ? *h : NAN;
  }

  const SelectedQuad* containing(double lon, double lat) const {
    return eval_.containing(lon, lat);
  }

  // The mesh point above (lon, lat) in quad q: its triangle found by
  // descending the 4-8 hierarchy to a triangle of the mesh.
  std::optional<Vec3> point(const SelectedQuad& q, double lon, double lat) {
    const size_t qi = index_.at(q.key);
    const geo::GeoBox b = q.key.bounds();
    const double cell = b.height() / n_;
    const double gx = (lon - b.west) / cell, gy = (b.north - lat) / cell;
    const int h = gx < n_ ? 0 : 1;
    const GridPos c{h * n_ + n_ / 2, n_ / 2}, nw{h * n_, 0}, ne{h * n_ + n_, 0},
        se{h * n_ + n_, n_}, sw{h * n_, n_};
    const GridPos roots[4][2] = {{nw, ne}, {ne, se}, {se, sw}, {sw, nw}};
    GridPos t[3];
    bool found = false;
    double w[3];
    for (const auto& r : roots) {
      if (inside(c, r[0], r[1], gx, gy, w)) {
        t[0] = c, t[1] = r[0], t[2] = r[1];
        found = true;
        break;
      }
    }
    if (!found) return std::nullopt;
    for (int depth = 0; depth < 40; ++depth) {
      if (triangles_[qi].contains(key(id(t[0]), id(t[1]), id(t[2])))) {
        Vec3 out;
        for (int k = 0; k < 3; ++k) {
          const auto [vlon, vlat] = lonlat(q, t[k]);
          out = out + ecef(vlon, vlat, height(q, t[k])) * w[k];
        }
        return out;
      }
      const GridPos m{(t[1].x + t[2].x) / 2, (t[1].y + t[2].y) / 2};
      const GridPos r = t[0], a = t[1], bb = t[2];
      if (inside(m, a, r, gx, gy, w)) {
        t[0] = m, t[1] = a, t[2] = r;
      } else if (inside(m, r, bb, gx, gy, w)) {
        t[0] = m, t[1] = r, t[2] = bb;
      } else {
        return std::nullopt;
      }
    }
    return std::nullopt;
  }

 private:
  static uint64_t key(uint32_t a, uint32_t b, uint32_t c) {
    uint32_t v[3] = {a, b, c};
    std::sort(v, v + 3);
    return uint64_t{v[0]} << 42 | uint64_t{v[1]} << 21 | v[2];
  }
  // Barycentric weights of (x, y) in triangle (p0, p1, p2), with a tolerance.
  static bool inside(GridPos p0, GridPos p1, GridPos p2, double x, double y, double* w) {
    const double d = double(p1.x - p0.x) * (p2.y - p0.y) - double(p2.x - p0.x) * (p1.y - p0.y);
    const double s = ((x - p0.x) * (p2.y - p0.y) - (p2.x - p0.x) * (y - p0.y)) / d;
    const double r = ((p1.x - p0.x) * (y - p0.y) - (x - p0.x) * (p1.y - p0.y)) / d;
    if (s < -1e-9 || r < -1e-9 || s + r > 1 + 1e-9) return false;
    w[0] = 1 - s - r, w[1] = s, w[2] = r;
    return true;
  }

  TerrainModel& terrain_;
  const Selection& selection_;
  const RefinedMesh& mesh_;
  MeshEvaluator eval_;
  int n_;
  std::vector<std::unordered_set<uint64_t>> triangles_;
  std::unordered_map<geo::TileKey, size_t, geo::TileKeyHash> index_;
};

struct Measured {
  size_t compared = 0;
  double worst = 0;
};

// Projected distance between finest samples and the refined mesh above them,
// for `count` random finest samples on screen.
Measured measure(Terrain& t, const View& view, const Selection& s, const RefinedMesh& m,
                 int count) {
  RefinedEvaluator eval(t.terrain, s, m);
  const auto& finest = t.store.index(t.terrain.data_max_level()).entries();
  std::mt19937 rng(7);
  Measured out;
  for (int k = 0; k < count; ++k) {
    const auto& e = finest[rng() % finest.size()];
    auto tile = t.terrain.tile(e.key);
    EXPECT_TRUE(tile);
    const int i = static_cast<int>(rng() % t.terrain.tile_width()),
              j = static_cast<int>(rng() % t.terrain.tile_height());
    const double lon = t.store.grid().sample_lon(e.key, i),
                 lat = t.store.grid().sample_lat(e.key, j);
    const float h = (*tile)->f32()[static_cast<size_t>(j + t.terrain.border()) * (*tile)->width() +
                                   i + t.terrain.border()];
    const SelectedQuad* q = eval.containing(lon, lat);
    if (!q) continue;  // culled
    const auto on_mesh = eval.point(*q, lon, lat);
    EXPECT_TRUE(on_mesh) << "no triangle of " << q->key.to_string() << " holds " << lon << ","
                         << lat;
    if (!on_mesh) continue;
    double ax, ay, bx, by;
    if (!view.project(ecef(lon, lat, h), ax, ay) || !view.project(*on_mesh, bx, by)) continue;
    if (ax < 0 || ay < 0 || ax >= view.width || ay >= view.height) continue;
    out.worst = std::max(out.worst, std::hypot(ax - bx, ay - by));
    ++out.compared;
  }
  return out;
}

struct Case {
  const char* name;
  Terrain& (*terrain)();
  Camera camera;
  double pixel_error;
};

std::vector<Case> cases() {
  return {
      {"oblique", pyrenees, look_at(1.45, 42.55, 1500, 30000, 20, -35, 60, 640, 480), 1.0},
      {"low", pyrenees, look_at(1.6, 42.4, 1200, 15000, 200, -15, 60, 640, 480), 1.0},
      {"down", pyrenees, look_at(1.5, 42.6, 2000, 60000, 0, -80, 45, 512, 512), 2.0},
      {"grazing", pyrenees, look_at(1.3, 42.45, 1500, 8000, 100, -4, 60, 640, 480), 1.0},
      {"scotland", scotland, look_at(-3.2, 55.5, 300, 20000, 300, -30, 60, 640, 480), 1.0},
  };
}

TEST(Refine, Explore) {
  for (const Case& c : cases()) {
    Terrain& t = c.terrain();
    auto view = make_view(c.camera);
    ASSERT_TRUE(view);
    const Selection s = select(t, *view, c.pixel_error);
    for (RefineVariant v : {RefineVariant::kTopDown, RefineVariant::kBottomUp}) {
      const RefinedMesh m = refined(t, *view, s, c.pixel_error, v);
      const Measured e = measure(t, *view, s, m, 4000);
      printf(
          "%s %s: %zu quads (%lu quad-mode tris), %lu tris, %lu marks, %u tiles, %.3f s, "
          "unresolved %lu (%.2f px), worst %.3f px over %zu\n",
          c.name, v == RefineVariant::kTopDown ? "top-down" : "bottom-up", s.quads.size(),
          (unsigned long)s.stats.triangles, (unsigned long)m.triangles(),
          (unsigned long)m.stats.marks_evaluated, m.stats.tiles_measured, m.stats.seconds,
          (unsigned long)m.stats.unresolved, m.stats.max_unresolved_pixels, e.worst, e.compared);
    }
  }
}

}  // namespace
}  // namespace relief::lod
