// The per-diamond errors refinement uses (diamond_errors.h) against their
// definition evaluated by brute force: for every diamond, the largest
// |its two triangles - the full mesh| over the full-mesh vertices in it and in
// every descendant (saturation), and the full mesh's height range over the
// same points, on windows of the Pyrenees data cut to small grids.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <vector>

#include "../ingest/built_stores.h"
#include "diamond_errors.h"
#include "relief/lod/mesh_topology.h"
#include "relief/lod/terrain_model.h"

namespace relief::lod {
namespace {

// A bordered tile of 2^k x 2^(k-1) samples cut from `source` at (x0, y0).
tiles::Raster crop(const tiles::Raster& source, int border, int k, int x0, int y0) {
  const int w = (1 << k) + 2 * border, h = (1 << (k - 1)) + 2 * border;
  tiles::Raster out(tiles::SampleType::Float32, 1, w, h);
  for (int y = 0; y < h; ++y) {
    for (int x = 0; x < w; ++x) {
      out.f32()[static_cast<size_t>(y) * w + x] =
          source.f32()[static_cast<size_t>(y + y0) * source.width() + x + x0];
    }
  }
  return out;
}

struct Reference {
  double error = 0, lo = INFINITY, hi = -INFINITY;
};

// Diamond `c` and its descendants inside the grid, by their definition.
void brute_force(const MarkGrid& grid, const std::vector<double>& fm, GridPoint c,
                 std::vector<char>& seen, Reference& out) {
  if (seen[grid.id(c)]) return;
  seen[grid.id(c)] = 1;
  const Diamond d = grid.diamond(c);
  const GridPoint e0 = d.ends[0], e1 = d.ends[1];
  // Twice the signed area of (o, u, v).
  auto cr = [](GridPoint o, GridPoint u, GridPoint v) {
    return double(u.x - o.x) * (v.y - o.y) - double(u.y - o.y) * (v.x - o.x);
  };
  const int32_t r = d.size;
  for (int32_t y = std::max(0, c.y - r); y <= std::min(grid.n(), c.y + r); ++y) {
    for (int32_t x = std::max(0, c.x - r); x <= std::min(2 * grid.n(), c.x + r); ++x) {
      if ((x + y) % 2) continue;  // not a full-mesh vertex
      const int32_t dx = std::abs(x - c.x), dy = std::abs(y - c.y);
      if (d.kind != MarkKind::kDiagonal && dx + dy > r) continue;
      const GridPoint p{x, y};
      double value = NAN;  // in a triangle (apex, e0, e1): barycentric weights
      for (const GridPoint& a : d.apexes) {
        if (!grid.inside(a)) continue;
        const double area = cr(a, e0, e1);
        const double w0 = cr(a, p, e1) / area, w1 = cr(a, e0, p) / area, wa = 1 - w0 - w1;
        if (w0 < -1e-12 || w1 < -1e-12 || wa < -1e-12) continue;
        value = wa * fm[grid.id(a)] + w0 * fm[grid.id(e0)] + w1 * fm[grid.id(e1)];
      }
      ASSERT_FALSE(std::isnan(value)) << "a point of the diamond in no triangle";
      const double f = fm[grid.id(p)];
      out.error = std::max(out.error, std::abs(value - f));
      out.lo = std::min(out.lo, f);
      out.hi = std::max(out.hi, f);
    }
  }
  if (d.kind == MarkKind::kDiagonal && d.size == 1) return;
  for (const GridPoint& child : d.children(c)) {
    if (grid.inside(child)) brute_force(grid, fm, child, seen, out);
  }
}

TEST(DiamondErrors, EqualTheirDefinitionByBruteForce) {
  const tiles::Store& store = relief::testing::pyrenees_store();
  MeshTopology mesh(4);
  TerrainModel terrain(&store, mesh, uint64_t{64} << 20);
  // The finest tile with the steepest relief (the Pyrenees' main ridge).
  const auto& entries = store.index(store.manifest().max_level).entries();
  const geo::TileKey key =
      std::max_element(entries.begin(), entries.end(), [](const auto& a, const auto& b) {
        return a.max - a.min < b.max - b.min;
      })->key;
  const TerrainModel::TilePtr tile = *terrain.tile(key);
  ASSERT_TRUE(tile);
  const int border = terrain.border();
  int diamonds = 0;
  double largest = 0;
  for (int k = 2; k <= 5; ++k) {
    const MarkGrid grid(k);
    for (const auto& [x0, y0] : {std::pair{0, 0}, std::pair{100, 50}, std::pair{300, 150}}) {
      const tiles::Raster window = crop(*tile, border, k, x0, y0);
      const DiamondErrors errors = measure_diamonds(grid, window, border);
      std::vector<double> fm(grid.count(), 0.0);
      for (int32_t y = 0; y <= grid.n(); ++y) {
        for (int32_t x = y % 2; x <= 2 * grid.n(); x += 2) {
          fm[grid.id({x, y})] = TerrainModel::bilinear(window, border, x / 2.0, y / 2.0);
        }
      }
      for (int c = 0; c < grid.classes(); ++c) {
        grid.for_each_in_class(c, [&](GridPoint p) {
          Reference want;
          std::vector<char> seen(grid.count(), 0);
          brute_force(grid, fm, p, seen, want);
          ASSERT_GE(double{errors.at[grid.slot(p)].error}, want.error - 1e-9)
              << k << " " << p.x << "," << p.y;
          EXPECT_LE(double{errors.at[grid.slot(p)].error}, want.error + 1e-3)
              << k << " " << p.x << "," << p.y;
          EXPECT_EQ(static_cast<double>(errors.at[grid.slot(p)].lo), std::floor(want.lo))
              << k << " " << p.x << "," << p.y;
          EXPECT_EQ(static_cast<double>(errors.at[grid.slot(p)].hi), std::ceil(want.hi))
              << k << " " << p.x << "," << p.y;
          ++diamonds;
          largest = std::max(largest, double{errors.at[grid.slot(p)].error});
        });
      }
    }
  }
  EXPECT_GT(diamonds, 1000);
  EXPECT_GT(largest, 10.0);  // real relief, not a flat window
}

}  // namespace
}  // namespace relief::lod
