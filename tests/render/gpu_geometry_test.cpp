// The GPU-resident geometry, read back from the vertex shader with transform
// feedback: positions built in float on the GPU project where the double
// computation does at every level and anywhere on Earth, vertices shared by
// quads (of the same or different levels, with the mesh topology or refined
// meshes) are bit-identical, and a view that does not change uploads nothing.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstring>
#include <map>
#include <random>
#include <set>

#include <fmt/format.h>

#include "../ingest/built_stores.h"
#include "height_slopes.h"
#include "quad_records.h"
#include "relief/lod/selection.h"
#include "relief/render/terrain_renderer.h"
#include "terrain_capture.h"
#include "tile_slots.h"

namespace relief::render {
namespace {

using geo::TileKey;

struct Gl {
  std::unique_ptr<GlContext> context;
  Gl() {
    auto c = GlContext::create_headless();
    if (!c) throw std::runtime_error(c.error().message);
    context = std::move(*c);
  }
};
Gl& gl() {
  static Gl g;
  return g;
}

// Quad-space vertices, in draw order, of the triangles of `selection`.
std::vector<lod::MeshVertex> drawn_vertices(const lod::MeshTopology& mesh,
                                            const lod::Selection& selection) {
  std::vector<lod::MeshVertex> out;
  for (const auto& q : selection.quads) {
    const uint32_t first = mesh.first_index(q.finer_sides), n = mesh.index_count(q.finer_sides);
    for (uint32_t i = first; i < first + n; ++i) out.push_back(mesh.vertices()[mesh.indices()[i]]);
  }
  return out;
}

lod::Vec3 exact_position(const TileKey& key, const lod::MeshVertex& v) {
  const geo::GeoBox b = key.bounds();
  return lod::ecef(b.west + v.u * b.width(), b.north - v.v * b.height(), 0);
}

TEST(GpuGeometry, PositionsProjectAsTheDoubleComputationAtEveryLevelAnywhere) {
  gl();
  const lod::MeshTopology mesh(2);
  lod::TerrainModel bare(nullptr, mesh, 1 << 20);
  auto renderer = TerrainRenderer::create(bare, nullptr);
  ASSERT_TRUE(renderer) << renderer.error().message;
  const double places[][2] = {{0.001, 0.001},   {1.5, 42.5}, {179.9999, 10},
                              {-179.9999, -33}, {25, 85},    {-60, -80}};
  for (int level = 0; level <= 20; ++level) {
    for (const auto& place : places) {
      SCOPED_TRACE(fmt::format("level {} at {},{}", level, place[0], place[1]));
      const uint32_t n = 1u << level;
      const TileKey key{level, std::min(n - 1, static_cast<uint32_t>((place[0] + 180) / 360 * n)),
                        std::min(n - 1, static_cast<uint32_t>((90 - place[1]) / 180 * n))};
      // The same quad twice: alone, and with every side and corner shared
      // with coarser quads (its border vertices anchored on its parent's corners).
      lod::Selection s;
      s.quads.push_back({key});
      if (level > 0) s.quads.push_back({key, 0, 15, 15});
      // An eye above the quad, about a quad's size away (1 m at least).
      const geo::GeoBox b = key.bounds();
      const double size = b.height() * 111000;
      auto view = lod::make_view(lod::Camera{(b.west + b.east) / 2, (b.south + b.north) / 2,
                                             1 + 0.3 * size, 30, -60, 0, 60, 1920, 1080});
      ASSERT_TRUE(view) << view.error().message;
      auto got = capture_positions(**renderer, *view, s, {});
      ASSERT_TRUE(got) << got.error().message;
      const std::vector<lod::MeshVertex> vertices = drawn_vertices(mesh, s);
      ASSERT_EQ(got->size(), vertices.size() * 3);
      double worst_px = 0, worst_m = 0;
      size_t projected = 0;
      for (size_t i = 0; i < vertices.size(); ++i) {
        const lod::Vec3 exact = exact_position(key, vertices[i]);
        const lod::Vec3 gpu =
            view->eye + lod::Vec3{(*got)[3 * i], (*got)[3 * i + 1], (*got)[3 * i + 2]};
        worst_m = std::max(worst_m, lod::length(gpu - exact));
        double ex, ey, gx, gy;
        if (view->project(exact, ex, ey) && view->project(gpu, gx, gy) && ex > -100 && ex < 2020 &&
            ey > -100 && ey < 1180) {  // on screen
          worst_px = std::max({worst_px, std::abs(ex - gx), std::abs(ey - gy)});
          ++projected;
        }
      }
      EXPECT_GT(projected, 0u);
      EXPECT_LT(worst_px, 0.01) << "m " << worst_m << " size " << size;
      // Relative to the quad's size (float offsets from a corner).
      EXPECT_LT(worst_m, 1e-6 * size + 1e-3) << worst_m;
    }
  }
}

}  // namespace
}  // namespace relief::render

namespace relief::render {
namespace {

size_t count_rgb(const std::vector<uint8_t>& rgba, uint8_t r, uint8_t g, uint8_t b) {
  size_t n = 0;
  for (size_t p = 0; p < rgba.size(); p += 4)
    n += rgba[p] == r && rgba[p + 1] == g && rgba[p + 2] == b;
  return n;
}

// Frames of different sizes one after the other (buffers grow between them):
// every one covers the ground.
TEST(GpuGeometry, FramesOfGrowingSelectionsCoverTheGround) {
  gl();
  const lod::MeshTopology mesh(2);
  lod::TerrainModel bare(nullptr, mesh, 1 << 20);
  auto renderer = TerrainRenderer::create(bare, nullptr);
  ASSERT_TRUE(renderer) << renderer.error().message;
  auto target = make_offscreen_target(64, 48);
  ASSERT_TRUE(target);
  auto view = lod::make_view(lod::Camera{1.45, 42.55, 3600, 20, -50, 0, 60, 64, 48});
  ASSERT_TRUE(view);
  RenderOptions o;
  o.sky = {1, 0, 1};
  for (int level : {0, 3, 5, 2, 6}) {
    SCOPED_TRACE(level);
    auto s = lod::restricted_quadtree(bare, [&](const TileKey& k) { return k.level < level; });
    ASSERT_TRUE(s);
    auto f = (*renderer)->draw(*view, *s, **target, o);
    ASSERT_TRUE(f) << f.error().message;
    auto pixels = (*target)->read_rgba();
    ASSERT_TRUE(pixels);
    EXPECT_EQ(count_rgb(*pixels, 255, 0, 255), 0u);
  }
}

}  // namespace
}  // namespace relief::render

namespace relief::render {
namespace {

// A restricted quadtree refined at random over the Pyrenees store, deeper than
// its finest level: neighbours of different levels everywhere there.
lod::Selection random_pyrenees_quadtree(lod::TerrainModel& terrain, unsigned seed) {
  auto split = [seed](const TileKey& k) {
    const geo::GeoBox b = k.bounds(), pyrenees{0.9, 41.0, 2.1, 43.0};
    if (!b.intersects(pyrenees) || k.level >= 12) return false;
    std::mt19937_64 rng(seed * 1000003u + k.morton() * 31 + static_cast<uint64_t>(k.level));
    return k.level < 6 || std::uniform_real_distribution<double>(0, 1)(rng) < 0.55;
  };
  auto s = lod::restricted_quadtree(terrain, split);
  if (!s) throw std::runtime_error(s.error().message);
  return std::move(*s);
}

// The mesh topology's triangles of every quad as a refined mesh on the grid
// of level refinement + 1 (whose vertices are the topology's corners,
// centres and midpoints).
lod::RefinedMesh as_refined(const lod::MeshTopology& mesh, const lod::Selection& s) {
  lod::RefinedMesh r;
  r.grid_k = mesh.refinement() + 1;
  for (const auto& q : s.quads) {
    lod::RefinedQuad rq{static_cast<uint32_t>(r.indices.size()), 0};
    const uint32_t first = mesh.first_index(q.finer_sides), n = mesh.index_count(q.finer_sides);
    for (uint32_t i = first; i < first + n; ++i) {
      const lod::MeshVertex& v = mesh.vertices()[mesh.indices()[i]];
      const auto col = static_cast<uint32_t>(v.u * static_cast<float>(r.grid_columns() - 1)),
                 row = static_cast<uint32_t>(v.v * static_cast<float>(r.grid_rows() - 1));
      r.indices.push_back(lod::grid_vertex_id(r.grid_k, col, row));
    }
    rq.index_count = n;
    r.quads.push_back(rq);
  }
  return r;
}

// Every grid cell cut into two triangles (counter-clockwise seen from above).
lod::RefinedMesh uniform_refined(int k, size_t quads) {
  lod::RefinedMesh r;
  r.grid_k = k;
  const uint32_t cols = r.grid_columns(), rows = r.grid_rows();
  std::vector<uint32_t> one;
  for (uint32_t j = 0; j + 1 < rows; ++j) {
    for (uint32_t i = 0; i + 1 < cols; ++i) {
      const uint32_t nw = lod::grid_vertex_id(k, i, j), ne = lod::grid_vertex_id(k, i + 1, j),
                     sw = lod::grid_vertex_id(k, i, j + 1),
                     se = lod::grid_vertex_id(k, i + 1, j + 1);
      one.insert(one.end(), {nw, sw, se, nw, se, ne});
    }
  }
  for (size_t q = 0; q < quads; ++q) {
    r.quads.push_back({static_cast<uint32_t>(r.indices.size()), static_cast<uint32_t>(one.size())});
    r.indices.insert(r.indices.end(), one.begin(), one.end());
  }
  return r;
}

// Quad-space vertices, in draw order, of a refined mesh.
std::vector<lod::MeshVertex> refined_vertices(const lod::RefinedMesh& r) {
  std::vector<lod::MeshVertex> out;
  for (const auto& q : r.quads) {
    for (uint32_t i = q.first_index; i < q.first_index + q.index_count; ++i) {
      const lod::GridVertexPosition p = lod::grid_vertex_position(r.grid_k, r.indices[i]);
      out.push_back({static_cast<float>(p.i) / static_cast<float>(r.grid_columns() - 1),
                     static_cast<float>(p.j) / static_cast<float>(r.grid_rows() - 1)});
    }
  }
  return out;
}

// Checks that every point drawn by more than one quad got the same bits from
// each; returns how many points quads of different levels share.
size_t expect_shared_vertices_bit_identical(const lod::Selection& s,
                                            const std::vector<size_t>& vertices_per_quad,
                                            const std::vector<lod::MeshVertex>& vertices,
                                            const std::vector<float>& positions) {
  struct Seen {
    float xyz[3];
    int level;
  };
  std::map<std::pair<double, double>, Seen> seen;
  size_t v = 0, across_levels = 0, mismatches = 0;
  for (size_t q = 0; q < s.quads.size(); ++q) {
    const geo::GeoBox b = s.quads[q].key.bounds();
    for (size_t i = 0; i < vertices_per_quad[q]; ++i, ++v) {
      double lon = b.west + vertices[v].u * b.width();
      const double lat = b.north - vertices[v].v * b.height();
      if (std::abs(lat) == 90) continue;  // every longitude is the pole
      if (lon >= 180) lon -= 360;
      Seen now{{positions[3 * v], positions[3 * v + 1], positions[3 * v + 2]},
               s.quads[q].key.level};
      auto [it, fresh] = seen.emplace(std::pair{lon, lat}, now);
      if (fresh) continue;
      if (std::memcmp(it->second.xyz, now.xyz, sizeof now.xyz) != 0) {
        if (++mismatches < 5) {
          ADD_FAILURE() << "vertex " << lon << "," << lat << " of " << s.quads[q].key.to_string()
                        << ": " << now.xyz[0] - it->second.xyz[0] << " "
                        << now.xyz[1] - it->second.xyz[1] << " " << now.xyz[2] - it->second.xyz[2];
        }
      }
      across_levels += it->second.level != now.level;
    }
  }
  EXPECT_EQ(mismatches, 0u);
  return across_levels;
}

class PyreneesGeometry : public ::testing::Test {
 protected:
  PyreneesGeometry() : terrain_(&testing::pyrenees_store(), mesh_, uint64_t{256} << 20) { gl(); }
  lod::View view(int w = 160, int h = 120) {
    auto v = lod::make_view(lod::look_at(1.5, 42.5, 1500, 40000, 0, -30, 60, w, h));
    if (!v) throw std::runtime_error(v.error().message);
    return *v;
  }
  const lod::MeshTopology mesh_{3};
  lod::TerrainModel terrain_;
};

TEST_F(PyreneesGeometry, SharedVerticesAreBitIdenticalAcrossLevelsWithHeights) {
  auto renderer = TerrainRenderer::create(terrain_, nullptr);
  ASSERT_TRUE(renderer) << renderer.error().message;
  RenderOptions o;
  o.exaggeration = 3;
  for (unsigned seed = 1; seed <= 3; ++seed) {
    SCOPED_TRACE(seed);
    const lod::Selection s = random_pyrenees_quadtree(terrain_, seed);
    auto got = capture_positions(**renderer, view(), s, o);
    ASSERT_TRUE(got) << got.error().message;
    std::vector<size_t> per_quad;
    for (const auto& q : s.quads) per_quad.push_back(mesh_.index_count(q.finer_sides));
    EXPECT_GT(expect_shared_vertices_bit_identical(s, per_quad, drawn_vertices(mesh_, s), *got),
              1000u);
    // The same triangles as a refined mesh: the same bits.
    const lod::RefinedMesh refined = as_refined(mesh_, s);
    auto again = capture_positions(**renderer, view(), s, o, &refined);
    ASSERT_TRUE(again) << again.error().message;
    EXPECT_TRUE(*again == *got);
  }
}

TEST_F(PyreneesGeometry, RefinedMeshesDrawTheTopologysImageAndUniformGridsConform) {
  auto renderer = TerrainRenderer::create(terrain_, nullptr);
  ASSERT_TRUE(renderer) << renderer.error().message;
  auto target = make_offscreen_target(160, 120);
  ASSERT_TRUE(target);
  lod::SelectionOptions so;
  auto s = lod::select_quads(view(), terrain_, so);
  ASSERT_TRUE(s);
  ASSERT_GT(s->quads.size(), 20u);
  auto topology = (*renderer)->draw(view(), *s, **target, {});
  ASSERT_TRUE(topology);
  const auto want = (*target)->read_rgba();
  const lod::RefinedMesh refined = as_refined(mesh_, *s);
  auto f = (*renderer)->draw(view(), *s, **target, {}, &refined);
  ASSERT_TRUE(f) << f.error().message;
  EXPECT_TRUE(*(*target)->read_rgba() == *want);
  EXPECT_EQ(f->triangles, topology->triangles);
  EXPECT_EQ(f->draw_calls, 1u);

  // Quads of one level with the uniform triangulation of a grid: no cracks
  // (a view of the ground only) and shared vertices bit-identical.
  auto same_level = lod::restricted_quadtree(terrain_, [](const TileKey& k) {
    return k.level < 9 && k.bounds().intersects({1.0, 42.0, 2.0, 43.0});
  });
  ASSERT_TRUE(same_level);
  lod::Selection level9;
  for (const auto& q : same_level->quads) {
    if (q.key.level == 9) level9.quads.push_back({q.key});
  }
  ASSERT_GT(level9.quads.size(), 20u);
  const lod::RefinedMesh uniform = uniform_refined(4, level9.quads.size());
  auto ground = lod::make_view(lod::Camera{1.45, 42.55, 3600, 20, -50, 0, 60, 160, 120});
  ASSERT_TRUE(ground);
  RenderOptions magenta;
  magenta.sky = {1, 0, 1};
  ASSERT_TRUE((*renderer)->draw(*ground, level9, **target, magenta, &uniform));
  EXPECT_EQ(count_rgb(*(*target)->read_rgba(), 255, 0, 255), 0u);
  auto got = capture_positions(**renderer, *ground, level9, {}, &uniform);
  ASSERT_TRUE(got);
  std::vector<size_t> per_quad(level9.quads.size(), uniform.quads[0].index_count);
  expect_shared_vertices_bit_identical(level9, per_quad, refined_vertices(uniform), *got);
}

TEST_F(PyreneesGeometry, AStaticViewUploadsNothingAfterItsFirstFrame) {
  auto renderer = TerrainRenderer::create(terrain_, nullptr);
  ASSERT_TRUE(renderer) << renderer.error().message;
  auto target = make_offscreen_target(160, 120);
  ASSERT_TRUE(target);
  auto s = lod::select_quads(view(), terrain_, {});
  ASSERT_TRUE(s);
  auto first = (*renderer)->draw(view(), *s, **target, {});
  ASSERT_TRUE(first);
  EXPECT_GT(first->geometry_bytes, 0u);
  EXPECT_GT(first->texture_bytes, 0u);
  auto second = (*renderer)->draw(view(), *s, **target, {});
  ASSERT_TRUE(second);
  EXPECT_EQ(second->geometry_bytes, 0u);
  EXPECT_EQ(second->texture_bytes, 0u);
  EXPECT_EQ(second->uploads, 0u);
  // The eye moves, the selection stays: only the records (they hold the eye
  // offset), and the draw commands if their near-to-far order changed.
  auto moved = lod::make_view(lod::look_at(1.5, 42.5, 1500, 40010, 0, -30, 60, 160, 120));
  ASSERT_TRUE(moved);
  auto third = (*renderer)->draw(*moved, *s, **target, {});
  ASSERT_TRUE(third);
  EXPECT_TRUE(third->geometry_bytes == s->quads.size() * 352 ||
              third->geometry_bytes == s->quads.size() * (352 + 20))
      << third->geometry_bytes;
  EXPECT_EQ(third->texture_bytes, 0u);
  // Refined meshes: their indices once, then nothing.
  const lod::RefinedMesh refined = as_refined(mesh_, *s);
  auto r1 = (*renderer)->draw(*moved, *s, **target, {}, &refined);
  ASSERT_TRUE(r1);
  EXPECT_GE(r1->geometry_bytes, refined.indices.size() * 4);
  auto r2 = (*renderer)->draw(*moved, *s, **target, {}, &refined);
  ASSERT_TRUE(r2);
  EXPECT_EQ(r2->geometry_bytes, 0u);
  EXPECT_EQ(r2->texture_bytes, 0u);
}

// The first layers of the elevation arrays come with the renderer, not with
// the first frame's first tile (on llvmpipe here their allocation took ~36 ms
// of the first frame of a flight): a frame that draws nothing finds them.
TEST_F(PyreneesGeometry, TheRendererAllocatesItsFirstLayersBeforeAnyFrame) {
  auto renderer = TerrainRenderer::create(terrain_, nullptr);
  ASSERT_TRUE(renderer) << renderer.error().message;
  auto target = make_offscreen_target(160, 120);
  ASSERT_TRUE(target);
  auto f = (*renderer)->draw(view(), lod::Selection{}, **target, {});
  ASSERT_TRUE(f) << f.error().message;
  const int b = terrain_.border();
  const uint64_t tile_bytes = static_cast<uint64_t>(terrain_.tile_width() + 2 * b) *
                              static_cast<uint64_t>(terrain_.tile_height() + 2 * b) * (4 + 4);
  EXPECT_EQ(f->gpu_slots, static_cast<uint32_t>(TileSlots::kFirstLayers));
  EXPECT_EQ(f->gpu_allocated_bytes, TileSlots::kFirstLayers * tile_bytes);
  EXPECT_EQ(f->uploads, 0u);
  EXPECT_EQ(f->gpu_textures, 0u);
  EXPECT_EQ(f->triangles, 0u);
}

TEST_F(PyreneesGeometry, StatisticsOfAKnownSelection) {
  auto renderer = TerrainRenderer::create(terrain_, nullptr);
  ASSERT_TRUE(renderer) << renderer.error().message;
  auto target = make_offscreen_target(160, 120);
  ASSERT_TRUE(target);
  // Level 6 everywhere (4096 quads), down to level 11 over the Pyrenees.
  auto split = [](const TileKey& k) {
    return k.level < 6 || (k.level < 11 && k.bounds().intersects({0.9, 41.0, 2.1, 43.0}));
  };
  auto selected = lod::restricted_quadtree(terrain_, split);
  ASSERT_TRUE(selected);
  const lod::Selection& s = *selected;
  ASSERT_GT(s.quads.size(), 4000u);
  uint64_t triangles = 0;
  std::set<TileKey> tiles;
  for (const auto& q : s.quads) {
    triangles += mesh_.triangle_count(q.finer_sides);
    for (const lod::DataWindow& w : {terrain_.window(q.key), terrain_.parent_window(q.key)}) {
      if (w.tile) tiles.insert(*w.tile);
    }
  }
  auto f = (*renderer)->draw(view(), s, **target, {});
  ASSERT_TRUE(f) << f.error().message;
  EXPECT_LE(f->draw_calls, 64u);
  EXPECT_EQ(f->quads, s.quads.size());
  EXPECT_EQ(f->triangles, triangles);
  EXPECT_EQ(f->pixels, 160u * 120u);
  EXPECT_DOUBLE_EQ(f->triangles_per_pixel(), static_cast<double>(triangles) / (160 * 120));
  const int b = terrain_.border();
  // R32F heights and their RG16F slopes.
  const uint64_t tile_bytes = static_cast<uint64_t>(terrain_.tile_width() + 2 * b) *
                              static_cast<uint64_t>(terrain_.tile_height() + 2 * b) * (4 + 4);
  EXPECT_EQ(f->gpu_textures, tiles.size());
  EXPECT_EQ(f->uploads, tiles.size());
  EXPECT_EQ(f->texture_bytes, tiles.size() * tile_bytes);
  EXPECT_EQ(f->gpu_bytes, tiles.size() * tile_bytes);
  EXPECT_GE(f->gpu_slots, tiles.size());
  EXPECT_EQ(f->gpu_allocated_bytes, f->gpu_slots * tile_bytes);
  // Per-quad records and draw commands, the mesh, the quad ids.
  EXPECT_GE(f->geometry_bytes, s.quads.size() * (352 + 20 + 4));
}

}  // namespace
}  // namespace relief::render

namespace relief::render {
namespace {

TEST(GpuGeometry, MalformedRefinedMeshesAreErrorsNotDraws) {
  gl();
  const lod::MeshTopology mesh(2);
  lod::TerrainModel bare(nullptr, mesh, 1 << 20);
  auto renderer = TerrainRenderer::create(bare, nullptr);
  ASSERT_TRUE(renderer);
  auto target = make_offscreen_target(16, 16);
  ASSERT_TRUE(target);
  auto view = lod::make_view(lod::Camera{1.45, 42.55, 3600, 20, -50, 0, 60, 16, 16});
  ASSERT_TRUE(view);
  lod::Selection s;
  s.quads.push_back({TileKey{0, 0, 0}});
  auto expect_error = [&](const lod::RefinedMesh& r, const std::string& needle) {
    auto f = (*renderer)->draw(*view, s, **target, {}, &r);
    ASSERT_FALSE(f) << needle;
    EXPECT_NE(f.error().message.find(needle), std::string::npos) << f.error().message;
  };
  lod::RefinedMesh r;
  r.grid_k = 1;  // 5 x 3 vertices
  expect_error(r, "0 quads for a selection of 1");
  r.indices = {0, 5, 6};
  r.quads = {{0, 3}};
  ASSERT_TRUE((*renderer)->draw(*view, s, **target, {}, &r));
  r.quads = {{1, 3}};
  expect_error(r, "outside");
  r.quads = {{0, 2}};
  expect_error(r, "outside");
  r.quads = {{0, 3}};
  r.indices = {0, 5, 15};
  expect_error(r, "vertex id past the 15");
  r.grid_k = 40;
  expect_error(r, "grid level 40");
}

}  // namespace
}  // namespace relief::render

namespace relief::render {
namespace {

// The GPU cache (L3) as texture-array layers: within its budget least
// recently used first out, layers reused, the frame's tiles pinned.
TEST(TileSlots, EvictsTheLeastRecentlyUsedAndReusesTheirLayers) {
  gl();
  const std::vector<float> pixels(4 * 4, 1.0f);  // 64 bytes of heights, 64 of slopes
  TileSlots slots(3 * 128, 4);
  gl::Uploads uploads;
  auto key = [](uint32_t x) { return TextureKey{TileKey{5, x, 0}, false}; };
  slots.begin_frame();
  for (uint32_t x = 0; x < 3; ++x) ASSERT_TRUE(slots.insert(key(x), 4, 4, pixels.data(), uploads));
  EXPECT_EQ(slots.used_bytes(), 3u * 128);
  EXPECT_EQ(uploads.textures, 3u * 128);
  EXPECT_EQ(slots.slopes().layers(), slots.heights().layers());
  EXPECT_EQ(slots.heights().layers(), 4);  // as many as the budget holds, at most the GL limit
  slots.begin_frame();
  ASSERT_TRUE(slots.find(key(0)));  // pinned, most recent
  const int layer1 = *slots.find(key(1));
  slots.begin_frame();
  ASSERT_TRUE(slots.find(key(0)));
  ASSERT_TRUE(slots.insert(key(3), 4, 4, pixels.data(), uploads));  // evicts 2, the oldest
  ASSERT_TRUE(slots.insert(key(4), 4, 4, pixels.data(), uploads));  // evicts 1
  EXPECT_FALSE(slots.find(key(1)));
  EXPECT_FALSE(slots.find(key(2)));
  EXPECT_EQ(slots.evicted(), 2u);
  EXPECT_EQ(slots.count(), 3u);
  EXPECT_LE(slots.used_bytes(), slots.budget_bytes());
  // Evicted layers are reused: nothing grew.
  EXPECT_EQ(slots.heights().layers(), 4);
  EXPECT_TRUE(*slots.find(key(3)) == layer1 || *slots.find(key(4)) == layer1);
  // Tiles of another size, and more pinned tiles than layers, are errors.
  const std::vector<float> big(8 * 8, 0.0f);
  auto wrong = slots.insert(key(9), 8, 8, big.data(), uploads);
  ASSERT_FALSE(wrong);
  EXPECT_NE(wrong.error().message.find("8x8, the store's others 4x4"), std::string::npos);
  slots.begin_frame();
  for (uint32_t x = 10; x < 14; ++x)
    ASSERT_TRUE(slots.insert(key(x), 4, 4, pixels.data(), uploads));
  auto full = slots.insert(key(14), 4, 4, pixels.data(), uploads);
  ASSERT_FALSE(full);
  EXPECT_NE(full.error().message.find("more than 4 elevation tiles"), std::string::npos);
}

// The texels of one layer of a texture array of R32F 4 x 4 layers.
std::vector<float> layer_texels(const gl::TextureArray& a, int layer) {
  std::vector<float> out(static_cast<size_t>(a.width()) * a.height());
  glGetTextureSubImage(a.id(), 0, 0, 0, layer, a.width(), a.height(), 1, GL_RED, GL_FLOAT,
                       static_cast<GLsizei>(out.size() * sizeof(float)), out.data());
  return out;
}

TEST(TextureArray, GrowsWithoutLosingItsLayers) {
  gl();
  gl::TextureArray a(GL_R32F, GL_RED, GL_FLOAT, 4);
  a.set_layer_size(4, 4);
  a.reserve(2);
  gl::Uploads uploads;
  const std::vector<float> ones(16, 1.0f), twos(16, 2.0f);
  a.upload(0, ones.data(), uploads);
  a.upload(1, twos.data(), uploads);
  a.reserve(5);
  EXPECT_EQ(a.layers(), 5);
  EXPECT_EQ(layer_texels(a, 0), ones);
  EXPECT_EQ(layer_texels(a, 1), twos);
  EXPECT_EQ(uploads.textures, 2u * 64);  // the copy is GPU to GPU
  EXPECT_EQ(gl_error(), "");
}

// A full array of uploaded tiles is not copied into a larger one while the
// frame pins fewer than half its layers: the least recently used unpinned
// layer is reused. It grows (keeping every layer) once a frame pins half.
TEST(TileSlots, AFullArrayReusesALayerUnlessTheFramePinsHalfOfIt) {
  gl();
  TileSlots slots(uint64_t{1} << 30, 4096);
  gl::Uploads uploads;
  auto key = [](uint32_t x) { return TextureKey{TileKey{12, x, 0}, false}; };
  auto pixels = [](uint32_t x) { return std::vector<float>(16, static_cast<float>(x)); };
  const uint32_t n = TileSlots::kFirstLayers;
  std::vector<int> layer_of;
  slots.begin_frame();
  for (uint32_t x = 0; x < n; ++x) {
    auto layer = slots.insert(key(x), 4, 4, pixels(x).data(), uploads);
    ASSERT_TRUE(layer);
    layer_of.push_back(*layer);
  }
  EXPECT_EQ(slots.heights().layers(), static_cast<int>(n));  // one allocation, no growth
  EXPECT_EQ(slots.pinned(false), static_cast<int>(n));
  // The next frame pins a quarter of the tiles and needs one more: tile n/4,
  // the least recently used of the others, gives its layer.
  slots.begin_frame();
  for (uint32_t x = 0; x < n / 4; ++x) ASSERT_TRUE(slots.find(key(x)));
  EXPECT_EQ(slots.pinned(false), static_cast<int>(n / 4));
  auto added = slots.insert(key(n), 4, 4, pixels(n).data(), uploads);
  ASSERT_TRUE(added);
  EXPECT_EQ(*added, layer_of[n / 4]);
  EXPECT_EQ(slots.heights().layers(), static_cast<int>(n));
  EXPECT_FALSE(slots.find(key(n / 4)));
  EXPECT_EQ(slots.evicted(), 1u);
  EXPECT_EQ(layer_texels(slots.heights(), *added), pixels(n));
  EXPECT_EQ(slots.slopes().layers(), static_cast<int>(n));
  // A frame that pins half the layers makes the array grow; no layer is lost.
  slots.begin_frame();
  for (uint32_t x = n / 2; x < n; ++x) ASSERT_TRUE(slots.find(key(x)));
  ASSERT_TRUE(slots.insert(key(n + 1), 4, 4, pixels(n + 1).data(), uploads));
  EXPECT_EQ(slots.heights().layers(), static_cast<int>(2 * n));
  EXPECT_EQ(slots.slopes().layers(), static_cast<int>(2 * n));
  EXPECT_EQ(slots.evicted(), 1u);
  for (uint32_t x : {0u, n / 2, n - 1, n, n + 1}) {
    const auto layer = slots.find(key(x));
    ASSERT_TRUE(layer) << x;
    EXPECT_EQ(layer_texels(slots.heights(), *layer), pixels(x)) << x;
  }
}

// Allocated ahead of the first tile (the renderer knows the store's tile
// size): the tiles then take free layers, nothing grows, and a tile of
// another size is refused as before.
TEST(TileSlots, AllocatedAheadTheFirstTilesTakeItsLayers) {
  gl();
  TileSlots slots(uint64_t{1} << 30, 4096);
  slots.allocate(false, 4, 4);
  const int n = TileSlots::kFirstLayers;
  EXPECT_EQ(slots.heights().layers(), n);
  EXPECT_EQ(slots.slopes().layers(), n);
  EXPECT_EQ(slots.imagery().layers(), 0);
  EXPECT_EQ(slots.count(), 0u);
  EXPECT_EQ(slots.used_bytes(), 0u);
  slots.allocate(false, 8, 8);  // sized already: nothing
  EXPECT_EQ(slots.heights().width(), 4);
  gl::Uploads uploads;
  slots.begin_frame();
  const std::vector<float> pixels(16, 3.0f);
  auto layer = slots.insert(TextureKey{TileKey{3, 1, 0}, false}, 4, 4, pixels.data(), uploads);
  ASSERT_TRUE(layer);
  EXPECT_EQ(*layer, 0);
  EXPECT_EQ(layer_texels(slots.heights(), *layer), pixels);
  EXPECT_EQ(slots.heights().layers(), n);
  EXPECT_EQ(uploads.textures, 16u * (4 + 4));
  EXPECT_FALSE(slots.insert(TextureKey{TileKey{3, 2, 0}, false}, 5, 4, pixels.data(), uploads));
  EXPECT_EQ(gl_error(), "");
}

// The next growth's bytes are announced once per size, when a frame pins
// 3/8 of an array's layers (uploaded tiles grow once a frame pins half of a
// full array), for the heights' array and their slopes' apart.
TEST(TileSlots, AnnouncesTheNextGrowthBeforeItComes) {
  gl();
  TileSlots slots(uint64_t{1} << 30, 4096);
  std::vector<uint64_t> announced;
  slots.set_on_growth_ahead([&](uint64_t bytes) { announced.push_back(bytes); });
  gl::Uploads uploads;
  const std::vector<float> pixels(16, 1.0f);
  const uint64_t n = TileSlots::kFirstLayers;
  auto insert = [&](uint64_t x) {
    return slots.insert(TextureKey{TileKey{12, static_cast<uint32_t>(x), 0}, false}, 4, 4,
                        pixels.data(), uploads);
  };
  slots.begin_frame();
  for (uint64_t x = 0; x + 1 < 3 * n / 8; ++x) ASSERT_TRUE(insert(x));
  EXPECT_TRUE(announced.empty());
  ASSERT_TRUE(insert(3 * n / 8 - 1));
  // 2n layers of 4 x 4 texels: R32F heights and RG16F slopes.
  EXPECT_EQ(announced, (std::vector<uint64_t>{2 * n * 64, 2 * n * 64}));
  for (uint64_t x = 3 * n / 8; x < n; ++x) ASSERT_TRUE(insert(x));
  EXPECT_EQ(announced.size(), 2u);
  EXPECT_EQ(slots.heights().layers(), static_cast<int>(n));
  // The frame needs one more: the array grows as announced, and with n + 1
  // of its 2n layers pinned the growth after is announced.
  ASSERT_TRUE(insert(n));
  EXPECT_EQ(slots.heights().layers(), static_cast<int>(2 * n));
  EXPECT_EQ(announced, (std::vector<uint64_t>{2 * n * 64, 2 * n * 64, 4 * n * 64, 4 * n * 64}));
  ASSERT_TRUE(insert(n + 1));
  EXPECT_EQ(announced.size(), 4u);
  EXPECT_EQ(gl_error(), "");
}

// Tiles found resident count as the frame's pins too; a growth past what
// the budget holds is not announced.
TEST(TileSlots, AnnouncesOnFoundTilesAndNotPastTheBudget) {
  gl();
  const uint64_t n = TileSlots::kFirstLayers, tile = 4 * 4 * (4 + 4);
  TileSlots slots(2 * n * tile + tile, 4096);  // 2n layers and one more
  std::vector<uint64_t> announced;
  slots.set_on_growth_ahead([&](uint64_t bytes) { announced.push_back(bytes); });
  gl::Uploads uploads;
  const std::vector<float> pixels(16, 1.0f);
  auto insert = [&](uint64_t x) {
    return slots.insert(TextureKey{TileKey{12, static_cast<uint32_t>(x), 0}, false}, 4, 4,
                        pixels.data(), uploads);
  };
  auto find = [&](uint64_t x) {
    return slots.find(TextureKey{TileKey{12, static_cast<uint32_t>(x), 0}, false});
  };
  const uint64_t third = 3 * n / 8;  // pins that announce
  slots.begin_frame();
  for (uint64_t x = 0; x + 1 < third; ++x) ASSERT_TRUE(insert(x));
  EXPECT_TRUE(announced.empty());
  slots.begin_frame();
  ASSERT_TRUE(insert(third - 1));
  for (uint64_t x = 0; x + 2 < third; ++x) ASSERT_TRUE(find(x));
  EXPECT_TRUE(announced.empty());
  ASSERT_TRUE(find(third - 2));  // the frame's 3/8th pin, found
  EXPECT_EQ(announced, (std::vector<uint64_t>{2 * n * 64, 2 * n * 64}));
  // A frame of new tiles grows the array to 2n; pinning 3/8 of that, the
  // next growth would be past the budget: not announced.
  announced.clear();
  slots.begin_frame();
  for (uint64_t x = 1000; x <= 1000 + n; ++x) ASSERT_TRUE(insert(x));
  EXPECT_EQ(slots.heights().layers(), static_cast<int>(2 * n));
  EXPECT_GE(8 * slots.pinned(false), static_cast<int>(3 * 2 * n));
  EXPECT_TRUE(announced.empty());
  EXPECT_EQ(gl_error(), "");
}

// Composites (written on the GPU, costly to remake) are kept: their array
// grows, up to what the budget holds, rather than reuse a layer.
TEST(TileSlots, CompositesGrowTheArrayRatherThanGiveUpALayer) {
  gl();
  TileSlots slots(uint64_t{1} << 30, 4096);
  gl::Uploads uploads;
  auto key = [](uint32_t x) { return TextureKey{TileKey{12, x, 0}, true, 1}; };
  const uint32_t n = TileSlots::kFirstLayers;
  slots.begin_frame();
  for (uint32_t x = 0; x < n; ++x) ASSERT_TRUE(slots.insert(key(x), 4, 4, nullptr, uploads));
  slots.begin_frame();
  ASSERT_TRUE(slots.insert(key(n), 4, 4, nullptr, uploads));
  EXPECT_EQ(slots.imagery().layers(), static_cast<int>(2 * n));
  EXPECT_EQ(slots.evicted(), 0u);
  EXPECT_EQ(uploads.textures, 0u);
}

TEST(HeightSlopes, HalfFloatsRoundToNearestEvenAndSaturate) {
  EXPECT_EQ(to_half(0.0f), 0x0000);
  EXPECT_EQ(to_half(-0.0f), 0x8000);
  EXPECT_EQ(to_half(1.0f), 0x3c00);
  EXPECT_EQ(to_half(-2.0f), 0xc000);
  EXPECT_EQ(to_half(0.1f), 0x2e66);
  EXPECT_EQ(to_half(1234.5f), 0x64d2);          // (1 + 210.5 / 1024) * 2^10: a tie, to 210 (even)
  EXPECT_EQ(to_half(1.0f + 0x1p-11f), 0x3c00);  // half an ulp above 1: to 1 (even)
  EXPECT_EQ(to_half(1.0f + 3 * 0x1p-11f), 0x3c02);  // 1.5 ulps: to 2 ulps (even)
  EXPECT_EQ(to_half(65504.0f), 0x7bff);
  EXPECT_EQ(to_half(1e9f), 0x7bff);  // saturates: a slope, never infinite
  EXPECT_EQ(to_half(-1e9f), 0xfbff);
  EXPECT_EQ(to_half(0x1p-24f), 0x0001);  // the smallest subnormal
  EXPECT_EQ(to_half(0x1p-14f), 0x0400);  // the smallest normal
  EXPECT_EQ(to_half(std::nanf("")), 0x0000);
}

TEST(HeightSlopes, DifferencesAcrossEachSampleClampedAtTheEdges) {
  // 3 x 2 heights, rows running south.
  const std::vector<float> h = {1, 2,  4,  //
                                8, 16, 32};
  const std::vector<uint16_t> s = height_slopes(h, 3, 2);
  ASSERT_EQ(s.size(), 12u);
  const float expected[12] = {2 - 1,  8 - 1, 4 - 1,  16 - 2, 4 - 2,   32 - 4,  //
                              16 - 8, 8 - 1, 32 - 8, 16 - 2, 32 - 16, 32 - 4};
  for (size_t i = 0; i < 12; ++i) EXPECT_EQ(s[i], to_half(expected[i])) << i;
}

// The interior rows take a vectorised path (eight samples at a time where
// the CPU converts to half floats itself): every half equals to_half() of
// the clamped differences, saturation, NaN, subnormals and -0 included.
TEST(HeightSlopes, EveryPathGivesTheHalvesOfTheClampedDifferences) {
  std::mt19937 rng(3);
  for (const auto& [w, h] :
       {std::pair{37, 9}, std::pair{514, 6}, std::pair{8, 4}, std::pair{2, 5}}) {
    std::vector<float> heights(static_cast<size_t>(w) * h);
    for (float& v : heights) {
      switch (rng() % 6) {
        case 0:
          v = std::nanf("");
          break;
        case 1:
          v = rng() % 2 ? 1e9f : -1e9f;
          break;
        case 2:
          v = std::ldexp(static_cast<float>(rng() % 100), -30);
          break;
        case 3:
          v = -0.0f;
          break;
        default:
          v = static_cast<float>(rng() % 100000) / 7.0f - 5000.0f;
      }
    }
    auto at = [&](int x, int y) {
      return heights[static_cast<size_t>(std::clamp(y, 0, h - 1)) * w + std::clamp(x, 0, w - 1)];
    };
    const std::vector<uint16_t> s = height_slopes(heights, w, h);
    ASSERT_EQ(s.size(), heights.size() * 2);
    for (int y = 0; y < h; ++y) {
      for (int x = 0; x < w; ++x) {
        const size_t i = (static_cast<size_t>(y) * w + x) * 2;
        ASSERT_EQ(s[i], to_half(at(x + 1, y) - at(x - 1, y)))
            << w << "x" << h << " " << x << "," << y;
        ASSERT_EQ(s[i + 1], to_half(at(x, y + 1) - at(x, y - 1)))
            << w << "x" << h << " " << x << "," << y;
      }
    }
  }
}

// What the fragment shader shades with, on real tiles through the GL's own
// filtering: the one fetch of the slopes gives the height differences (and
// the shade) of the four fetches of the heights it replaces, anywhere in the
// tile, edges included.
TEST(HeightSlopes, OneFetchShadesAsTheFourHeightFetchesItReplaces) {
  gl();
  const char* source = R"(#version 450 core
layout(local_size_x = 64) in;
uniform sampler2DArray heights, slopes;
uniform int layer, border;
layout(std430, binding = 0) readonly buffer Points { vec2 points[]; };
layout(std430, binding = 1) writeonly buffer Results { vec4 results[]; };
vec3 at(sampler2DArray t, vec2 p) {
  return vec3((p + float(border)) / vec2(textureSize(t, 0).xy), float(layer));
}
float h(vec2 p) { return textureLod(heights, at(heights, p), 0.0).r; }
void main() {
  uint i = gl_GlobalInvocationID.x;
  if (i >= uint(points.length())) return;
  vec2 p = points[i];
  results[i] = vec4(h(p + vec2(1, 0)) - h(p - vec2(1, 0)), h(p + vec2(0, 1)) - h(p - vec2(0, 1)),
                    textureLod(slopes, at(slopes, p), 0.0).rg);
}
)";
  const GLuint shader = glCreateShader(GL_COMPUTE_SHADER);
  glShaderSource(shader, 1, &source, nullptr);
  glCompileShader(shader);
  GLint ok = 0;
  glGetShaderiv(shader, GL_COMPILE_STATUS, &ok);
  ASSERT_TRUE(ok);
  const GLuint program = glCreateProgram();
  glAttachShader(program, shader);
  glLinkProgram(program);
  glGetProgramiv(program, GL_LINK_STATUS, &ok);
  ASSERT_TRUE(ok);

  const lod::MeshTopology mesh(3);
  lod::TerrainModel terrain(&testing::pyrenees_store(), mesh, uint64_t{256} << 20);
  const int finest = terrain.data_max_level();
  TileSlots slots(uint64_t{1} << 30, 16);
  gl::Uploads uploads;
  slots.begin_frame();
  // Steep tiles of the Pyrenees: the finest level, and four levels up.
  for (int level : {finest, finest - 4}) {
    SCOPED_TRACE(level);
    const uint32_t n = 1u << level;
    const TileKey key{level, static_cast<uint32_t>((1.6 + 180) / 360 * n),
                      static_cast<uint32_t>((90 - 42.6) / 180 * n)};
    auto tile = terrain.tile(key);
    ASSERT_TRUE(tile && *tile) << key.to_string();
    auto layer = slots.insert({key, false}, (*tile)->width(), (*tile)->height(),
                              (*tile)->f32().data(), uploads);
    ASSERT_TRUE(layer) << layer.error().message;
    // Points in interior sample coordinates, as the vertex shader passes
    // them: random ones, and the corners and sides of the tile.
    const float w = static_cast<float>(terrain.tile_width()),
                hh = static_cast<float>(terrain.tile_height());
    std::vector<float> points = {0,     0, w, 0,      0, hh,     w,     hh,
                                 w / 2, 0, 0, hh / 2, w, hh / 2, w / 2, hh};
    std::mt19937 random(7);
    std::uniform_real_distribution<float> u(0, 1);
    while (points.size() < 2 * 4096) points.insert(points.end(), {u(random) * w, u(random) * hh});
    const size_t count = points.size() / 2;
    GLuint buffers[2];
    glCreateBuffers(2, buffers);
    glNamedBufferStorage(buffers[0], static_cast<GLsizeiptr>(points.size() * sizeof(float)),
                         points.data(), 0);
    glNamedBufferStorage(buffers[1], static_cast<GLsizeiptr>(count * 4 * sizeof(float)), nullptr,
                         0);
    glUseProgram(program);
    glBindTextureUnit(0, slots.heights().id());
    glBindTextureUnit(1, slots.slopes().id());
    glUniform1i(glGetUniformLocation(program, "heights"), 0);
    glUniform1i(glGetUniformLocation(program, "slopes"), 1);
    glUniform1i(glGetUniformLocation(program, "layer"), *layer);
    glUniform1i(glGetUniformLocation(program, "border"), terrain.border());
    glBindBufferBase(GL_SHADER_STORAGE_BUFFER, 0, buffers[0]);
    glBindBufferBase(GL_SHADER_STORAGE_BUFFER, 1, buffers[1]);
    glDispatchCompute(static_cast<GLuint>((count + 63) / 64), 1, 1);
    glMemoryBarrier(GL_BUFFER_UPDATE_BARRIER_BIT);
    std::vector<float> results(count * 4);
    glGetNamedBufferSubData(buffers[1], 0, static_cast<GLsizeiptr>(results.size() * sizeof(float)),
                            results.data());
    glDeleteBuffers(2, buffers);
    ASSERT_EQ(gl_error(), "");

    // The shade of the fragment shader (sun from the north-west, 45 degrees
    // up) for a sample spacing of this level at 42.6 degrees north.
    const double spacing = key.bounds().height() / terrain.tile_height() * M_PI / 180 * 6371000.0;
    auto shade = [&](double dx, double dy, double exaggeration) {
      dx *= exaggeration / (2 * spacing * std::cos(42.6 * M_PI / 180));
      dy *= exaggeration / (2 * spacing);
      const double normal = std::sqrt(dx * dx + dy * dy + 1), sun = std::sqrt(2 + 1.414 * 1.414);
      return std::clamp((dx + dy + 1.414) / (normal * sun), 0.0, 1.0);
    };
    double worst_metres = 0, worst_shade = 0, steepest = 0;
    for (size_t i = 0; i < count; ++i) {
      const float* r = &results[4 * i];
      // The differences themselves differ by the GL's sub-texel precision
      // (llvmpipe: 8-bit filter weights) times the differences between texels.
      worst_metres =
          std::max({worst_metres, std::abs(double{r[2]} - r[0]), std::abs(double{r[3]} - r[1])});
      steepest = std::max(steepest, std::abs(static_cast<double>(r[0])) / (2 * spacing));
      for (double e : {1.0, 3.0, 10.0}) {
        const double error = std::abs(shade(r[2], r[3], e) - shade(r[0], r[1], e));
        worst_shade = std::max(worst_shade, error);
        EXPECT_LT(error, 1e-3) << "at " << points[2 * i] << "," << points[2 * i + 1]
                               << ", exaggeration " << e;  // a quarter of a grey level
      }
    }
    EXPECT_GT(steepest, 0.5);  // steep terrain, not a flat test
    std::cout << fmt::format("level {}: differences within {:.4f} m, shade within {:.2e}\n", level,
                             worst_metres, worst_shade);
  }
  glDeleteProgram(program);
  glDeleteShader(shader);
}

// Draws go nearest quad first (so llvmpipe's depth test spares the shading
// of what is hidden): a large quad under the eye before a small one nearby,
// before a small one far away.
TEST(QuadRecords, NearnessOrdersTheQuadUnderTheEyeFirst) {
  auto key_at = [](int level, double lon, double lat) {
    const uint32_t n = 1u << level;
    return TileKey{level, static_cast<uint32_t>((lon + 180) / 360 * n),
                   static_cast<uint32_t>((90 - lat) / 180 * n)};
  };
  QuadRecords records;
  const lod::Vec3 eye = lod::ecef(1.5, 42.5, 2000);
  const float under = nearness(records.make({key_at(6, 1.5, 42.5)}, eye)),
              nearby = nearness(records.make({key_at(12, 1.6, 42.5)}, eye)),
              far = nearness(records.make({key_at(12, 3, 42.5)}, eye));
  EXPECT_LT(under, nearby);
  EXPECT_LT(nearby, far);
  EXPECT_NEAR(far, 123000, 3000);  // 1.5 degrees of longitude at 42.5 north, less the quad's reach
}

}  // namespace
}  // namespace relief::render
