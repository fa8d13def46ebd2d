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
#include "headless_gl.h"
#include "relief/lod/selection.h"
#include "relief/render/terrain_renderer.h"
#include "terrain_capture.h"
#include "tile_slots.h"

namespace relief::render {
namespace {

using geo::TileKey;

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
  headless_gl();
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
  headless_gl();
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
  PyreneesGeometry() : terrain_(&testing::pyrenees_store(), mesh_, uint64_t{256} << 20) {
    headless_gl();
  }
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
  headless_gl();
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
