// Vertex ids of refined meshes (refined_mesh.h): a bijection onto the grid's
// vertex count, and an order in which neighbours stay together for a
// software rasteriser's vertex cache.
#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <vector>

#include "refine_fixtures.h"
#include "relief/lod/grid_vertex_ids.h"
#include "relief/lod/mesh_topology.h"
#include "relief/lod/refined_mesh.h"

namespace relief::lod {
namespace {

TEST(GridVertexId, IsABijectionOntoTheGridsVertexCountAndRoundTrips) {
  for (int k = 0; k <= 11; ++k) {
    const uint32_t columns = (2u << k) + 1, rows = (1u << k) + 1;
    std::vector<bool> seen(static_cast<size_t>(columns) * rows, false);
    for (uint32_t j = 0; j < rows; ++j) {
      for (uint32_t i = 0; i < columns; ++i) {
        const uint32_t id = grid_vertex_id(k, i, j);
        ASSERT_LT(id, seen.size()) << "k " << k << " (" << i << ", " << j << ")";
        ASSERT_FALSE(seen[id]) << "k " << k << " (" << i << ", " << j << ")";
        seen[id] = true;
        const GridVertexPosition p = grid_vertex_position(k, id);
        ASSERT_EQ(p.i, i) << "k " << k << " id " << id;
        ASSERT_EQ(p.j, j) << "k " << k << " id " << id;
      }
    }
  }
}

TEST(GridVertexId, AnAlignedBlockOf16By16VerticesHas256ConsecutiveIds) {  // in some order
  const int k = 6;
  for (uint32_t bj = 0; bj < (1u << k); bj += 16) {
    for (uint32_t bi = 0; bi < (2u << k); bi += 16) {
      std::vector<uint32_t> ids;
      for (uint32_t j = bj; j < bj + 16; ++j) {
        for (uint32_t i = bi; i < bi + 16; ++i) ids.push_back(grid_vertex_id(k, i, j));
      }
      std::sort(ids.begin(), ids.end());
      EXPECT_EQ(ids.back() - ids.front(), 255u) << "block (" << bi << ", " << bj << ")";
      EXPECT_EQ(ids.front() % 256, 0u) << "block (" << bi << ", " << bj << ")";
    }
  }
}

// Vertices shaded by Mesa's draw module (llvmpipe) for one draw: its indices
// in segments of 1023, each with a cleared direct-mapped cache of 256 entries
// keyed by the id modulo 256 (draw_pt_vsplit.c).
uint64_t shaded(const std::vector<uint32_t>& ids) {
  uint64_t misses = 0;
  for (size_t start = 0; start < ids.size(); start += 1023) {
    std::array<uint32_t, 256> cache;
    cache.fill(~0u);
    for (size_t i = start; i < std::min(ids.size(), start + 1023); ++i) {
      uint32_t& slot = cache[ids[i] % 256];
      if (slot != ids[i]) {
        slot = ids[i];
        ++misses;
      }
    }
  }
  return misses;
}

// The refined meshes of the shared views, drawn quad by quad through that
// cache: 0.6 vertices shaded per triangle, about as few as the segments allow
// (ids row by row: 1.7-1.8, as llvmpipe counted in bench/view's flight).
TEST(GridVertexId, ASoftwareRasterisersVertexCacheShadesFewerThanOneVertexPerTriangle) {
  for (const testing::Case& c : testing::cases()) {
    testing::Terrain& t = c.terrain();
    const View view = *make_view(c.camera);
    const Selection s = testing::select(t, view, c.pixel_error);
    const RefinedMesh m = testing::refined(t, view, s, c.pixel_error, RefineVariant::kTopDown);
    uint64_t ours = 0, row_major = 0;
    for (const RefinedQuad& q : m.quads) {
      const auto first = m.indices.begin() + q.first_index;
      std::vector<uint32_t> ids(first, first + q.index_count), rows;
      for (const uint32_t id : ids) {
        const GridVertexPosition p = grid_vertex_position(m.grid_k, id);
        rows.push_back(p.j * m.grid_columns() + p.i);
      }
      ours += shaded(ids);
      row_major += shaded(rows);
    }
    const double triangles = static_cast<double>(m.triangles());
    ASSERT_GT(triangles, 1000) << c.name;
    EXPECT_LT(static_cast<double>(ours) / triangles, 0.7) << c.name;
    EXPECT_LT(static_cast<double>(ours), 0.5 * static_cast<double>(row_major)) << c.name;
  }
}

// The quads mode's fixed meshes keep their row-by-row numbering: through the
// same cache it shades about as few vertices as the order of first use (the
// best a renumbering could reach for this triangle order), since a quad's
// corner rows of 2^(r+1) + 1 vertices are far shorter than the cache. At the
// default level 4: 0.73-0.77 against 0.68-0.71 per triangle (docs/rendering.md).
TEST(MeshTopologyIds, AQuadMeshShadesAboutAsFewVerticesAsTheOrderOfFirstUse) {
  for (int r = 2; r <= 5; ++r) {
    const MeshTopology mesh(r);
    for (int mask = 0; mask < 16; ++mask) {
      const auto first = mesh.indices().begin() + mesh.first_index(mask);
      const std::vector<uint32_t> ids(first, first + mesh.index_count(mask));
      std::vector<uint32_t> renumbered, order(mesh.vertices().size(), ~0u);
      uint32_t next = 0;
      for (const uint32_t id : ids) {
        if (order[id] == ~0u) order[id] = next++;
        renumbered.push_back(order[id]);
      }
      const double triangles = static_cast<double>(mesh.triangle_count(mask));
      const double ours = static_cast<double>(shaded(ids)) / triangles;
      EXPECT_LT(ours, 0.8) << "r " << r << " mask " << mask;
      EXPECT_LT(ours, 1.12 * static_cast<double>(shaded(renumbered)) / triangles)
          << "r " << r << " mask " << mask;
    }
  }
}

}  // namespace
}  // namespace relief::lod
