// The mesh of random restricted quadtrees over the whole globe: every edge is
// shared by exactly two triangles (none only along the poles), so there are
// no T-junctions and no cracks by construction; neighbouring quads differ by
// at most one level.
#include <gtest/gtest.h>

#include <algorithm>
#include <map>
#include <random>
#include <set>

#include "relief/lod/selection.h"

namespace relief::lod {
namespace {

using Point = std::pair<double, double>;  // lon, lat

Point position(const geo::TileKey& key, const MeshVertex& v) {
  const geo::GeoBox b = key.bounds();
  double lon = b.west + v.u * b.width();
  const double lat = b.north - v.v * b.height();
  if (lon >= 180) lon -= 360;  // the antimeridian is one line
  return {lon, lat};
}

TEST(Conformity, RandomRestrictedQuadtreesGiveWatertightMeshes) {
  const MeshTopology mesh(2);
  TerrainModel bare(nullptr, mesh, 1 << 20);  // the ellipsoid: levels 0..6
  ASSERT_EQ(bare.max_level(), 6);
  for (unsigned seed = 1; seed <= 12; ++seed) {
    SCOPED_TRACE(seed);
    auto split = [seed](const geo::TileKey& k) {
      std::mt19937_64 rng(seed * 1000003u + k.morton() * 31 + static_cast<uint64_t>(k.level));
      return k.level < 2 || std::uniform_real_distribution<double>(0, 1)(rng) < 0.4;
    };
    auto selection = restricted_quadtree(bare, split);
    ASSERT_TRUE(selection) << selection.error().message;
    std::set<geo::TileKey> leaves;
    for (const auto& q : selection->quads) leaves.insert(q.key);
    // The leaves tile the globe and neighbours differ by at most one level.
    double area = 0;
    for (const auto& q : selection->quads) {
      area += std::ldexp(1.0, -2 * q.key.level);
      for (int dy = -1; dy <= 1; ++dy) {
        for (int dx = -1; dx <= 1; ++dx) {
          auto n = q.key.neighbour(dx, dy);
          if (!n) continue;
          for (geo::TileKey k = *n;; k = *k.parent()) {
            if (leaves.count(k)) {
              EXPECT_GE(k.level, q.key.level - 1) << q.key.to_string();
              break;
            }
            if (k.level == 0) break;
          }
        }
      }
    }
    EXPECT_DOUBLE_EQ(area, 1.0);
    // The neighbour index array is symmetric: whoever I list lists me.
    for (size_t i = 0; i < selection->quads.size(); ++i) {
      for (int32_t n : selection->quads[i].neighbours) {
        if (n < 0) continue;
        const auto& other = selection->quads[static_cast<size_t>(n)].neighbours;
        EXPECT_NE(std::find(other.begin(), other.end(), static_cast<int32_t>(i)), other.end())
            << selection->quads[i].key.to_string() << " lists "
            << selection->quads[n].key.to_string();
      }
    }
    EXPECT_GT(selection->quads.size(), 50u);
    // Every edge of every triangle, by its exact end points.
    std::map<std::pair<Point, Point>, int> edges;
    for (const auto& q : selection->quads) {
      const auto& idx = mesh.indices();
      const uint32_t first = mesh.first_index(q.finer_sides),
                     count = mesh.index_count(q.finer_sides);
      for (uint32_t t = first; t < first + count; t += 3) {
        for (int e = 0; e < 3; ++e) {
          Point a = position(q.key, mesh.vertices()[idx[t + e]]);
          Point b = position(q.key, mesh.vertices()[idx[t + (e + 1) % 3]]);
          if (b < a) std::swap(a, b);
          ++edges[{a, b}];
        }
      }
    }
    size_t checked = 0;
    for (const auto& [edge, n] : edges) {
      const bool on_pole =
          std::abs(edge.first.second) == 90 && edge.first.second == edge.second.second;
      if (on_pole) continue;
      ASSERT_EQ(n, 2) << "edge (" << edge.first.first << "," << edge.first.second << ")-("
                      << edge.second.first << "," << edge.second.second << ")";
      ++checked;
    }
    EXPECT_GT(checked, 1000u);
  }
}

TEST(Conformity, BorderVariantsSplitExactlyTheirSides) {
  const MeshTopology mesh(3);
  EXPECT_EQ(mesh.triangle_count(0), 16u * 8 * 4);
  EXPECT_EQ(mesh.triangle_count(kWest), 16u * 8 * 4 + 8);
  EXPECT_EQ(mesh.triangle_count(kNorth | kSouth), 16u * 8 * 4 + 32);
  EXPECT_EQ(mesh.triangle_count(15), 16u * 8 * 4 + 48);
}

}  // namespace
}  // namespace relief::lod
