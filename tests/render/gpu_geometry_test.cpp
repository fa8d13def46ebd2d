// The GPU-resident geometry, read back from the vertex shader with transform
// feedback: positions built in float on the GPU project where the double
// computation does at every level and anywhere on Earth, vertices shared by
// quads (of the same or different levels, with the mesh topology or refined
// meshes) are bit-identical, and a view that does not change uploads nothing.
#include <gtest/gtest.h>

#include <cmath>
#include <cstring>
#include <map>
#include <random>
#include <set>

#include <fmt/format.h>

#include "../ingest/built_stores.h"
#include "relief/lod/selection.h"
#include "relief/render/terrain_renderer.h"
#include "terrain_capture.h"

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
