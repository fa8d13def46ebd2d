// Elevation layers of different depths fused at draw time (a coarse layer
// with a finer one inside it, as ETOPO5 with the Pyrenees): the store of
// sparse depth (pipeline/fused_elevation.h, TerrainModel::window). A coarse
// layer built from N41E001 and N42E001 three levels short of their finest,
// and N42E001 alone at its finest: the views across 42N see the fine layer
// and the coarse-only ground south of it. Checked brute force as
// fused_layers_test does for layers of one depth: every sample of the
// deepest data at its place projects within the threshold of the drawn mesh;
// and no crack (every vertex shared by two quads gets bit-identical heights
// from both), where the data level changes too.
#include <gtest/gtest.h>

#include <cmath>
#include <map>
#include <random>
#include <set>

#include "../ingest/built_stores.h"
#include "../support/test_support.h"
#include "relief/lod/mesh_evaluator.h"
#include "relief/lod/refine.h"
#include "relief/lod/refined_evaluator.h"
#include "relief/pipeline/fused_elevation.h"
#include "relief/tiles/full_mesh.h"

namespace relief::lod {
namespace {

const tiles::Store& layer(const std::string& name, const std::string& file) {
  ingest::BuildOptions o;
  o.inputs = {relief::testing::data(file)};
  o.kind = tiles::DatasetKind::Elevation;
  return relief::testing::built_store(name, o);
}

const tiles::Store& fine_layer() {
  return layer("n42", "srtm/N42E001.hgt.zip");
}

const tiles::Store& coarse_layer() {
  ingest::BuildOptions o;
  o.inputs = {relief::testing::data("srtm/N41E001.hgt.zip"),
              relief::testing::data("srtm/N42E001.hgt.zip")};
  o.kind = tiles::DatasetKind::Elevation;
  o.max_level = fine_layer().manifest().max_level - 3;
  return relief::testing::built_store("pair-coarse", o);
}

tiles::Store fuse(const tiles::Store& coarse, const tiles::Store& fine, pipeline::FuseMode mode) {
  std::vector<pipeline::ElevationLayer> layers;
  layers.push_back({"coarse", coarse});
  layers.push_back({"fine", fine});
  ThreadExecutor executor;
  auto store = pipeline::fuse_elevation_layers(std::move(layers), mode, executor);
  if (!store) throw std::runtime_error(store.error().message);
  return std::move(*store);
}

// The coarse layer first, as `relief render COARSE --elevation FINE`.
const tiles::Store& sparse(pipeline::FuseMode mode) {
  static const tiles::Store first = fuse(coarse_layer(), fine_layer(), pipeline::FuseMode::First);
  if (mode == pipeline::FuseMode::First) return first;
  static const tiles::Store mean = fuse(coarse_layer(), fine_layer(), pipeline::FuseMode::Blend);
  return mean;
}

struct Case {
  Camera camera;
  double pixel_error;
};
const Case kCases[] = {
    {look_at(1.5, 42.0, 1000, 30000, 10, -35, 60, 640, 480), 1.0},
    {look_at(1.3, 41.95, 800, 15000, 170, -15, 60, 640, 480), 1.0},
    {look_at(1.5, 42.0, 1000, 60000, 0, -80, 45, 512, 512), 2.0},
};

// A sample of the deepest data at (lon, lat): the store's deepest tile there
// (sparse depth: the data a quad below a tile without children draws).
struct Sample {
  double lon, lat;
  float h;
  int level;
};
std::optional<Sample> deepest_sample(const tiles::Store& store, TerrainModel& terrain, double lon,
                                     double lat) {
  for (int level = store.manifest().max_level; level >= 0; --level) {
    const geo::SampleIndex si = store.grid().locate(level, lon, lat);
    if (!store.has_tile(si.tile)) continue;
    auto tile = terrain.tile(si.tile);
    EXPECT_TRUE(tile);
    if (!tile || !*tile) return std::nullopt;
    const float h = (*tile)->f32()[static_cast<size_t>(si.j + terrain.border()) * (*tile)->width() +
                                   si.i + terrain.border()];
    return Sample{store.grid().sample_lon(si.tile, si.i), store.grid().sample_lat(si.tile, si.j), h,
                  level};
  }
  return std::nullopt;
}

// Within two samples of `level` of the data's outer edge (1E..2E, 41N..43N),
// which the geometric error leaves out by definition (fused_layers_test).
bool near_data_edge(const tiles::Store& store, const Sample& s, int level) {
  const geo::GeoBox& e = store.manifest().extent;
  const double margin = 2 * 180.0 / std::ldexp(store.grid().height(), std::min(level, s.level));
  return s.lon - e.west < margin || e.east - s.lon < margin || s.lat - e.south < margin ||
         e.north - s.lat < margin;
}

TEST(SparseLayers, TheFusedStoreHasSparseDepthAndTheFineLayersFinestLevel) {
  const tiles::Store& s = sparse(pipeline::FuseMode::First);
  EXPECT_TRUE(s.manifest().sparse_depth);
  EXPECT_EQ(s.manifest().max_level, fine_layer().manifest().max_level);
  // South of 42N only the coarse layer: the fine layer's finest level has no
  // tile there, and quads of that level draw a coarser tile's window (the
  // coarse layer upsampled: its own, or the padding around the fine layer).
  const int coarse = coarse_layer().manifest().max_level;
  const int finest = s.manifest().max_level;
  const geo::TileKey south = s.grid().locate(finest, 1.5, 41.3).tile;
  EXPECT_FALSE(s.has_tile(south));
  const MeshTopology mesh(4);
  TerrainModel terrain(&s, mesh, uint64_t{64} << 20);
  EXPECT_GE(terrain.data_level(south), coarse);
  EXPECT_LT(terrain.data_level(south), finest - 1);
  EXPECT_TRUE(terrain.draws_ancestor(south));
  EXPECT_FALSE(terrain.draws_ancestor(s.grid().locate(finest, 1.5, 42.5).tile));
}

// The level errors bound every tile's full mesh against the deepest data
// below it, wherever that is: the fine layer's finest tiles, or a tile with
// no child there (the coarse layer's finest, or the padding around the fine
// layer). Checked at random samples of the deepest data under each tile.
void expect_level_errors_bound(const tiles::Store& store, const tiles::Store& fine) {
  const MeshTopology mesh(4);
  TerrainModel terrain(&store, mesh, uint64_t{256} << 20);
  std::map<geo::TileKey, tiles::Raster> raw;  // NaN kept: the definition leaves nodata out
  auto read = [&](const geo::TileKey& k) -> const tiles::Raster& {
    auto it = raw.find(k);
    if (it == raw.end()) it = raw.emplace(k, relief::testing::must_read(store, k).raster).first;
    return it->second;
  };
  const int finest = store.manifest().max_level, b = store.grid().border();
  const int w = store.grid().width(), h = store.grid().height();
  std::mt19937 rng(11);
  std::uniform_real_distribution<double> unit(0, 1);
  size_t compared = 0, coarse_only = 0;
  for (int level = 3; level < finest; ++level) {
    for (const tiles::IndexEntry& e : store.index(level).entries()) {
      const double bound = *terrain.level_error(e.key);
      const tiles::Raster& tile = read(e.key);
      const geo::GeoBox box = e.key.bounds();
      for (int n = 0; n < 1000; ++n) {
        const double lon = box.west + unit(rng) * box.width();
        const double lat = box.south + unit(rng) * box.height();
        int deepest = finest;
        while (!store.has_tile(store.grid().locate(deepest, lon, lat).tile)) --deepest;
        if (deepest <= level) continue;  // this tile is the deepest data here
        const geo::SampleIndex si = store.grid().locate(deepest, lon, lat);
        const float v = read(si.tile).f32()[static_cast<size_t>(si.j + b) * (w + 2 * b) + si.i + b];
        const double slon = store.grid().sample_lon(si.tile, si.i);
        const double slat = store.grid().sample_lat(si.tile, si.j);
        const double x = (slon - box.west) / box.width() * w;
        const double y = (box.north - slat) / box.height() * h;
        if (std::isnan(v) || !tiles::full_mesh_stencil_valid(tile, b, x, y)) continue;
        const Sample s{slon, slat, v, deepest};
        if (near_data_edge(store, s, level)) continue;
        const double d = std::abs(tiles::full_mesh_height(tile, b, x, y) - v);
        ++compared;
        coarse_only +=
            !fine.has_tile(fine.grid().locate(fine.manifest().max_level, slon, slat).tile);
        ASSERT_LE(d, bound + 1e-3) << e.key.to_string() << " against " << si.tile.to_string();
      }
    }
  }
  EXPECT_GT(compared, 5000u);
  EXPECT_GT(coarse_only, 500u);
}

TEST(SparseLayers, LevelErrorsBoundTheFullMeshAgainstTheDeepestDataBelow) {
  expect_level_errors_bound(sparse(pipeline::FuseMode::First), fine_layer());
  // The fine layer south of 42N: N42's mountains are coarse-only.
  const tiles::Store& n41 = layer("n41", "srtm/N41E001.hgt.zip");
  expect_level_errors_bound(fuse(coarse_layer(), n41, pipeline::FuseMode::First), n41);
}

// Samples of the deepest data in each selected quad projected against the
// drawn mesh (`at(quad, lon, lat)`: the mesh point above), those on screen.
struct Measured {
  size_t compared = 0, coarse_only = 0;
  double worst = 0;
};
template <class Evaluator, class At>
Measured measure(const tiles::Store& store, TerrainModel& terrain, const View& view,
                 const Selection& selection, Evaluator& eval, int per_quad, At at) {
  std::mt19937 rng(5);
  std::uniform_real_distribution<double> unit(0, 1);
  Measured m;
  for (const SelectedQuad& q : selection.quads) {
    const geo::GeoBox b = q.key.bounds();
    for (int n = 0; n < per_quad; ++n) {
      const auto s = deepest_sample(store, terrain, b.west + unit(rng) * b.width(),
                                    b.south + unit(rng) * b.height());
      if (!s) continue;
      const SelectedQuad* in = eval.containing(s->lon, s->lat);
      if (!in || near_data_edge(store, *s, in->key.level)) continue;
      auto on_mesh = at(*in, s->lon, s->lat);
      EXPECT_TRUE(on_mesh) << on_mesh.error().message;
      if (!on_mesh) return m;
      double ax, ay, bx, by;
      if (!view.project(ecef(s->lon, s->lat, s->h), ax, ay) || !view.project(*on_mesh, bx, by))
        continue;
      if (ax < 0 || ay < 0 || ax >= view.width || ay >= view.height) continue;
      m.worst = std::max(m.worst, std::hypot(ax - bx, ay - by));
      ++m.compared;
      m.coarse_only += s->lat < 42 - 1e-6;  // N42E001 starts at 42N
    }
  }
  return m;
}

void expect_seen_and_within(const Measured& m, double pixel_error) {
  EXPECT_GT(m.compared, 1000u);
  EXPECT_GT(m.coarse_only, 100u) << "the view must see the coarse-only ground";
  EXPECT_GT(m.compared - m.coarse_only, 100u) << "the view must see the fine layer";
  EXPECT_LE(m.worst, pixel_error) << "worst " << m.worst << " px over " << m.compared;
}

void expect_guarantee(pipeline::FuseMode mode) {
  const tiles::Store& store = sparse(mode);
  const MeshTopology mesh(4);
  TerrainModel terrain(&store, mesh, uint64_t{256} << 20);
  for (const Case& c : kCases) {
    auto view = make_view(c.camera);
    ASSERT_TRUE(view);
    SelectionOptions o;
    o.pixel_error = c.pixel_error;
    o.mode = LodMode::quads;
    auto selection = select_quads(*view, terrain, o);
    ASSERT_TRUE(selection) << selection.error().message;
    EXPECT_LE(selection->stats.max_error_pixels, c.pixel_error);
    size_t below_a_leaf = 0;  // quads drawing a coarser tile's window above the finest level
    for (const SelectedQuad& q : selection->quads) {
      below_a_leaf += terrain.draws_ancestor(q.key) && q.key.level <= store.manifest().max_level;
    }
    EXPECT_GT(below_a_leaf, 0u);
    MeshEvaluator eval(terrain, *selection);
    expect_seen_and_within(measure(store, terrain, *view, *selection, eval, 40,
                                   [&](const SelectedQuad& q, double lon, double lat) {
                                     return eval.mesh_point(q, lon, lat);
                                   }),
                           c.pixel_error);
  }
}

TEST(SparseLayers, QuadMeshesKeepTheGuaranteeFirstValid) {
  expect_guarantee(pipeline::FuseMode::First);
}

TEST(SparseLayers, QuadMeshesKeepTheGuaranteeMean) {
  expect_guarantee(pipeline::FuseMode::Blend);
}

// No cracks: where the fine layer ends, quads of one level draw data of
// different levels (their own tile, or a coarser ancestor's); each side and
// corner takes the coarser data (SelectedQuad::parent_data_sides).
TEST(SparseLayers, SharedVerticesGetIdenticalHeightsWhereTheDataLevelChanges) {
  const tiles::Store& store = sparse(pipeline::FuseMode::First);
  const MeshTopology mesh(3);
  TerrainModel terrain(&store, mesh, uint64_t{256} << 20);
  size_t across_data_levels = 0;
  for (const Case& c : kCases) {
    auto view = make_view(c.camera);
    ASSERT_TRUE(view);
    SelectionOptions o;
    o.pixel_error = c.pixel_error;
    o.mode = LodMode::quads;
    auto selection = select_quads(*view, terrain, o);
    ASSERT_TRUE(selection) << selection.error().message;
    MeshEvaluator eval(terrain, Selection{});
    std::map<std::pair<double, double>, std::pair<double, geo::TileKey>> seen;
    size_t shared = 0;
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
        across_data_levels += terrain.data_level(it->second.second) != terrain.data_level(q.key);
        ASSERT_EQ(it->second.first, *height)
            << q.key.to_string() << " (data level " << terrain.data_level(q.key) << ") and "
            << it->second.second.to_string() << " (data level "
            << terrain.data_level(it->second.second) << ") at " << at.first << "," << at.second;
      }
    }
    EXPECT_GT(shared, 1000u);
  }
  EXPECT_GT(across_data_levels, 50u);
}

// Edge marks (the default LOD) refine each quad's own tile: the selection
// splits no quad whose tile has no child tile (its children would draw its
// window), and the padding makes such a tile's children all absent or all
// present wherever some layer has data. Refined until nothing is wanted
// split (split feedback, as fused_layers_test).
struct Refined {
  Selection selection;
  RefinedMesh mesh;
};
Refined refine_converged(const View& view, TerrainModel& terrain, RefineCache& cache,
                         double pixel_error) {
  SelectionOptions o;
  o.pixel_error = pixel_error;
  o.mode = LodMode::edge_marks;
  o.neighbour_indices = true;
  std::set<geo::TileKey> wanted;
  o.also_split = [&wanted](const geo::TileKey& key) { return wanted.contains(key); };
  RefineOptions ro;
  ro.pixel_error = pixel_error;
  ro.cache = &cache;
  Refined out;
  for (int round = 0; round < 6; ++round) {
    auto selection = select_quads(view, terrain, o);
    EXPECT_TRUE(selection) << selection.error().message;
    if (!selection) return {};
    auto mesh = refine(view, terrain, *selection, ro);
    EXPECT_TRUE(mesh) << mesh.error().message;
    if (!mesh) return {};
    out = {std::move(*selection), std::move(*mesh)};
    if (out.mesh.stats.split_wanted.empty()) break;
    wanted.insert(out.mesh.stats.split_wanted.begin(), out.mesh.stats.split_wanted.end());
  }
  return out;
}

bool has_child_tile(const tiles::Store& store, const geo::TileKey& key) {
  for (int c = 0; c < 4; ++c) {
    if (store.has_tile(key.child(c & 1, c >> 1))) return true;
  }
  return false;
}

TEST(SparseLayers, EveryTileHasNoChildOrEveryChildWithData) {
  const tiles::Store& store = sparse(pipeline::FuseMode::First);
  const tiles::Store& fine = fine_layer();
  const tiles::Store& coarse = coarse_layer();
  auto has_data = [](const tiles::Store& layer, const geo::TileKey& key) {
    const int m = std::max(0, key.level - layer.manifest().max_level);
    return layer.has_tile({key.level - m, key.x >> m, key.y >> m});
  };
  size_t padded = 0;  // children below the coarse layer's finest, not in the fine layer
  for (int level = 0; level < store.manifest().max_level; ++level) {
    for (const tiles::IndexEntry& e : store.index(level).entries()) {
      if (!has_child_tile(store, e.key)) continue;
      bool upsampled = false;
      for (int c = 0; c < 4; ++c) {
        const geo::TileKey child = e.key.child(c & 1, c >> 1);
        const bool data = has_data(fine, child) || has_data(coarse, child);
        EXPECT_EQ(store.has_tile(child), data) << child.to_string();
        upsampled |= data && !fine.has_tile(child) && level + 1 > coarse.manifest().max_level;
      }
      padded += upsampled;
    }
  }
  EXPECT_GT(padded, 5u);
}

void expect_refined_guarantee(pipeline::FuseMode mode) {
  const tiles::Store& store = sparse(mode);
  const MeshTopology mesh(4);
  TerrainModel terrain(&store, mesh, uint64_t{512} << 20);
  RefineCache cache(uint64_t{1} << 30);
  for (const Case& c : kCases) {
    auto view = make_view(c.camera);
    ASSERT_TRUE(view);
    SCOPED_TRACE(&c - kCases);
    Refined r = refine_converged(*view, terrain, cache, c.pixel_error);
    ASSERT_FALSE(r.selection.quads.empty());
    EXPECT_EQ(r.mesh.stats.too_coarse, 0u);
    // What stays wanted split is a tile without children next to a finer
    // quad (docs/rendering.md: diamonds on that side cannot be split).
    EXPECT_LE(r.mesh.stats.unresolved, 8u);
    for (const geo::TileKey& k : r.mesh.stats.split_wanted) {
      EXPECT_TRUE(store.has_tile(k) && !has_child_tile(store, k)) << k.to_string();
    }
    size_t leaves = 0;  // quads on a tile without children above the finest level
    for (const SelectedQuad& q : r.selection.quads) {
      ASSERT_FALSE(terrain.draws_ancestor(q.key)) << q.key.to_string();
      leaves += store.has_tile(q.key) && q.key.level < store.manifest().max_level &&
                !has_child_tile(store, q.key);
    }
    EXPECT_GT(leaves, 0u) << "the view must reach the coarse layer's finest tiles";
    RefinedEvaluator eval(terrain, r.selection, r.mesh);
    expect_seen_and_within(
        measure(store, terrain, *view, r.selection, eval, 1500,
                [&](const SelectedQuad& q, double lon, double lat) -> Result<Vec3> {
                  auto p = RELIEF_TRY(eval.point(q, lon, lat));
                  if (!p) return fail("no triangle of " + q.key.to_string());
                  return *p;
                }),
        c.pixel_error);
  }
}

TEST(SparseLayers, RefinedMeshesKeepTheGuaranteeFirstValid) {
  expect_refined_guarantee(pipeline::FuseMode::First);
}

TEST(SparseLayers, RefinedMeshesKeepTheGuaranteeMean) {
  expect_refined_guarantee(pipeline::FuseMode::Blend);
}

// No cracks with edge marks either: every grid vertex of a refined triangle
// shared by two quads (of equal or different levels, on tiles of the fine
// layer, the padding or the coarse layer) gets bit-identical heights.
TEST(SparseLayers, RefinedMeshesShareBitIdenticalVerticesWhereTheFineLayerEnds) {
  const tiles::Store& store = sparse(pipeline::FuseMode::First);
  const MeshTopology mesh(4);
  TerrainModel terrain(&store, mesh, uint64_t{512} << 20);
  RefineCache cache(uint64_t{1} << 30);
  size_t across_levels = 0;
  for (const Case& c : kCases) {
    auto view = make_view(c.camera);
    ASSERT_TRUE(view);
    const Refined r = refine_converged(*view, terrain, cache, c.pixel_error);
    RefinedEvaluator eval(terrain, r.selection, r.mesh);
    const int n = 1 << r.mesh.grid_k;
    std::map<std::pair<double, double>, std::pair<double, size_t>> seen;  // height, quad
    size_t shared = 0;
    for (size_t qi = 0; qi < r.selection.quads.size(); ++qi) {
      const SelectedQuad& q = r.selection.quads[qi];
      const RefinedQuad& rq = r.mesh.quads[qi];
      for (uint32_t i = rq.first_index; i < rq.first_index + rq.index_count; ++i) {
        const GridPos p = eval.pos(r.mesh.indices[i]);
        if (!(p.x == 0 || p.y == 0 || p.x == 2 * n || p.y == n)) continue;
        const auto h = eval.height(q, p);
        ASSERT_TRUE(h) << h.error().message;
        auto [it, fresh] = seen.try_emplace(eval.lonlat(q, p), *h, qi);
        if (fresh || it->second.second == qi) continue;
        ++shared;
        const SelectedQuad& other = r.selection.quads[it->second.second];
        across_levels += other.key.level != q.key.level;
        ASSERT_EQ(it->second.first, *h) << q.key.to_string() << " and " << other.key.to_string()
                                        << " at " << it->first.first << "," << it->first.second;
      }
    }
    EXPECT_GT(shared, 1000u);
  }
  EXPECT_GT(across_levels, 50u);
}

}  // namespace
}  // namespace relief::lod
