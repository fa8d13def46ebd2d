#include "diamond_errors.h"

#include <algorithm>
#include <cmath>

namespace relief::lod {

namespace {

int64_t cross(GridPoint o, GridPoint a, GridPoint b) {
  return int64_t{a.x - o.x} * (b.y - o.y) - int64_t{a.y - o.y} * (b.x - o.x);
}

// The plane through triangle (a, b, c) with heights ha, hb, hc, as
// h(p) = ha + gx (p.x - a.x) + gy (p.y - a.y).
struct TrianglePlane {
  GridPoint a;
  double ha = 0, gx = 0, gy = 0;
  TrianglePlane(GridPoint a_, GridPoint b, GridPoint c, double ha_, double hb, double hc)
      : a(a_), ha(ha_) {
    const double d = static_cast<double>(cross(a, b, c));
    const double bx = b.x - a.x, by = b.y - a.y, cx = c.x - a.x, cy = c.y - a.y;
    gx = ((hb - ha) * cy - (hc - ha) * by) / d;
    gy = ((hc - ha) * bx - (hb - ha) * cx) / d;
  }
  double at(int32_t x, int32_t y) const { return ha + gx * (x - a.x) + gy * (y - a.y); }
};

}  // namespace

DiamondErrors measure_diamonds(const MarkGrid& grid, const tiles::Raster& tile, int border) {
  const uint32_t count = grid.count();
  // The full mesh's heights at its vertices: points with x + y even (sample
  // centres and corners), the bilinear interpolation of the vertex shader.
  std::vector<float> fm(count, 0.0f);
  for (int32_t y = 0; y <= grid.n(); ++y) {
    for (int32_t x = y % 2; x <= 2 * grid.n(); x += 2) {
      fm[grid.id({x, y})] = TerrainModel::bilinear(tile, border, x / 2.0, y / 2.0);
    }
  }
  DiamondErrors out;
  out.error.assign(count, 0.0f);
  out.lo.assign(count, 0);
  out.hi.assign(count, 0);
  for (int c = 0; c < grid.classes(); ++c) {
    grid.for_each_in_class(c, [&](GridPoint centre) {
      const Diamond d = grid.diamond(centre);
      const GridPoint e0 = d.ends[0], e1 = d.ends[1];
      const double h0 = fm[grid.id(e0)], h1 = fm[grid.id(e1)];
      const int64_t side0 = cross(e0, e1, d.apexes[0]);
      // The triangles' planes (an apex outside the quad: never used).
      auto plane_of = [&](GridPoint a) {
        return grid.inside(a) ? TrianglePlane(a, e0, e1, fm[grid.id(a)], h0, h1)
                              : TrianglePlane(e0, e1, a, h0, h1, 0);
      };
      const TrianglePlane planes[2] = {plane_of(d.apexes[0]), plane_of(d.apexes[1])};
      const bool first_on_line = grid.inside(d.apexes[0]);
      double worst = 0, lo = INFINITY, hi = -INFINITY;
      const int32_t r = d.size;
      const int32_t x0 = std::max(0, centre.x - r), x1 = std::min(2 * grid.n(), centre.x + r);
      const int32_t y0 = std::max(0, centre.y - r), y1 = std::min(grid.n(), centre.y + r);
      const bool diagonal = d.kind == MarkKind::kDiagonal;
      for (int32_t y = y0; y <= y1; ++y) {
        // Axis diamonds: the points within L1 distance r of the centre.
        const int32_t reach = diagonal ? r : r - std::abs(y - centre.y);
        int32_t xa = std::max(x0, centre.x - reach), xb = std::min(x1, centre.x + reach);
        xa += (xa + y) & 1;  // full-mesh vertices: x + y even
        const float* row = &fm[grid.id({0, y})];
        for (int32_t x = xa; x <= xb; x += 2) {
          const int64_t side = cross(e0, e1, GridPoint{x, y});
          // The triangle holding the point; points on the hypotenuse take either.
          const bool first = side == 0 ? first_on_line : (side > 0) == (side0 > 0);
          const double v = row[x];
          worst = std::max(worst, std::abs(planes[first ? 0 : 1].at(x, y) - v));
          lo = std::min(lo, v);
          hi = std::max(hi, v);
        }
      }
      const uint32_t id = grid.id(centre);
      float error = static_cast<float>(worst);
      if (static_cast<double>(error) < worst) error = std::nextafter(error, INFINITY);
      int32_t ilo = static_cast<int32_t>(std::floor(lo)), ihi = static_cast<int32_t>(std::ceil(hi));
      if (c > 0) {  // saturate: children of class c - 1 inside the quad
        for (const GridPoint& child : d.children(centre)) {
          if (!grid.inside(child)) continue;
          const uint32_t cid = grid.id(child);
          error = std::max(error, out.error[cid]);
          ilo = std::min<int32_t>(ilo, out.lo[cid]);
          ihi = std::max<int32_t>(ihi, out.hi[cid]);
        }
      }
      out.error[id] = error;
      out.lo[id] = static_cast<int16_t>(std::clamp(ilo, -32768, 32767));
      out.hi[id] = static_cast<int16_t>(std::clamp(ihi, -32768, 32767));
    });
  }
  return out;
}

}  // namespace relief::lod
