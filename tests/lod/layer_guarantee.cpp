#include "layer_guarantee.h"

#include <gtest/gtest.h>

#include <cmath>
#include <random>
#include <set>

#include "relief/lod/mesh_evaluator.h"
#include "relief/lod/refine.h"
#include "relief/lod/refined_evaluator.h"

namespace relief::lod {
namespace {

// Pixels between a sample and the mesh point under it; -1 off screen.
double projected_distance(const View& view, const FinestSample& s, const Vec3& on_mesh) {
  double ax, ay, bx, by;
  if (!view.project(ecef(s.lon, s.lat, s.h), ax, ay) || !view.project(on_mesh, bx, by)) return -1;
  if (ax < 0 || ay < 0 || ax >= view.width || ay >= view.height) return -1;
  return std::hypot(ax - bx, ay - by);
}

// `samples_per_quad` random finest samples under each selected quad (a
// generator seeded with `seed`), each on screen within `pixel_error` of the
// mesh point `at(quad, lon, lat)` above it; more than 1000 of them on screen.
template <class Evaluator, class At>
void expect_within(const tiles::Store& store, TerrainModel& terrain, const View& view,
                   const Selection& selection, const Evaluator& eval, int samples_per_quad,
                   unsigned seed, double pixel_error, At at) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> unit(0, 1);
  size_t compared = 0;
  double worst = 0;
  for (const SelectedQuad& q : selection.quads) {
    const geo::GeoBox b = q.key.bounds();
    for (int n = 0; n < samples_per_quad; ++n) {
      const auto s = finest_sample(store, terrain, b.west + unit(rng) * b.width(),
                                   b.south + unit(rng) * b.height());
      if (!s) continue;
      const SelectedQuad* in = eval.containing(s->lon, s->lat);
      if (!in || near_data_edge(store, *s, in->key.level)) continue;
      const Result<Vec3> on_mesh = at(*in, s->lon, s->lat);
      ASSERT_TRUE(on_mesh) << on_mesh.error().message;
      const double d = projected_distance(view, *s, *on_mesh);
      if (d < 0) continue;
      worst = std::max(worst, d);
      ++compared;
    }
  }
  EXPECT_GT(compared, 1000u);
  EXPECT_LE(worst, pixel_error) << "worst " << worst << " px over " << compared;
}

}  // namespace

std::optional<FinestSample> finest_sample(const tiles::Store& store, TerrainModel& terrain,
                                          double lon, double lat) {
  const int finest = store.manifest().max_level;
  const geo::SampleIndex si = store.grid().locate(finest, lon, lat);
  if (!store.has_tile(si.tile)) return std::nullopt;
  auto tile = terrain.tile(si.tile);
  EXPECT_TRUE(tile);
  if (!tile || !*tile) return std::nullopt;
  const float h = (*tile)->f32()[static_cast<size_t>(si.j + terrain.border()) * (*tile)->width() +
                                 si.i + terrain.border()];
  return FinestSample{store.grid().sample_lon(si.tile, si.i),
                      store.grid().sample_lat(si.tile, si.j), h};
}

bool near_data_edge(const tiles::Store& store, const FinestSample& s, int level) {
  const geo::GeoBox& e = store.manifest().extent;
  const double margin = 2 * 180.0 / std::ldexp(store.grid().height(), level);
  return s.lon - e.west < margin || e.east - s.lon < margin || s.lat - e.south < margin ||
         e.north - s.lat < margin;
}

void expect_quads_keep_the_guarantee(const tiles::Store& store,
                                     std::span<const GuaranteeCase> cases, int samples_per_quad) {
  const MeshTopology mesh(4);
  TerrainModel terrain(&store, mesh, uint64_t{256} << 20);
  for (const GuaranteeCase& c : cases) {
    auto view = make_view(c.camera);
    ASSERT_TRUE(view);
    SelectionOptions o;
    o.pixel_error = c.pixel_error;
    o.mode = LodMode::quads;
    auto selection = select_quads(*view, terrain, o);
    ASSERT_TRUE(selection) << selection.error().message;
    EXPECT_LE(selection->stats.max_error_pixels, c.pixel_error);
    MeshEvaluator eval(terrain, *selection);
    expect_within(store, terrain, *view, *selection, eval, samples_per_quad, 5, c.pixel_error,
                  [&](const SelectedQuad& q, double lon, double lat) {
                    return eval.mesh_point(q, lon, lat);
                  });
  }
}

void expect_refined_meshes_keep_the_guarantee(const tiles::Store& store,
                                              std::span<const GuaranteeCase> cases,
                                              int samples_per_quad) {
  const MeshTopology mesh(4);
  TerrainModel terrain(&store, mesh, uint64_t{512} << 20);
  RefineCache cache(uint64_t{1} << 30);
  for (const GuaranteeCase& c : cases) {
    auto view = make_view(c.camera);
    ASSERT_TRUE(view);
    SelectionOptions o;
    o.pixel_error = c.pixel_error;
    o.mode = LodMode::edge_marks;
    o.neighbour_indices = true;
    // Quads the refinement wants split are split by the next selection (as
    // the frame loop's split feedback does; a built store needs it too).
    std::set<geo::TileKey> wanted;
    o.also_split = [&wanted](const geo::TileKey& key) { return wanted.contains(key); };
    RefineOptions ro;
    ro.pixel_error = c.pixel_error;
    ro.cache = &cache;
    Result<Selection> selection = fail("not selected");
    Result<RefinedMesh> refined = fail("not refined");
    for (int round = 0; round < 6; ++round) {
      selection = select_quads(*view, terrain, o);
      ASSERT_TRUE(selection) << selection.error().message;
      refined = refine(*view, terrain, *selection, ro);
      ASSERT_TRUE(refined) << refined.error().message;
      if (refined->stats.split_wanted.empty()) break;
      wanted.insert(refined->stats.split_wanted.begin(), refined->stats.split_wanted.end());
    }
    EXPECT_EQ(refined->stats.unresolved, 0u);
    EXPECT_EQ(refined->stats.too_coarse, 0u);
    RefinedEvaluator eval(terrain, *selection, *refined);
    expect_within(store, terrain, *view, *selection, eval, samples_per_quad, 7, c.pixel_error,
                  [&](const SelectedQuad& q, double lon, double lat) -> Result<Vec3> {
                    auto p = RELIEF_TRY(eval.point(q, lon, lat));
                    if (!p) return fail("no triangle of " + q.key.to_string());
                    return *p;
                  });
  }
}

}  // namespace relief::lod
