#include "diamond_errors.h"

#include <algorithm>
#include <cmath>

namespace relief::lod {

namespace {

int64_t cross(GridPoint o, GridPoint a, GridPoint b) {
  return int64_t{a.x - o.x} * (b.y - o.y) - int64_t{a.y - o.y} * (b.x - o.x);
}

// Height at p of the plane through the triangle (a, b, c) with heights ha, hb, hc.
double plane(GridPoint a, GridPoint b, GridPoint c, double ha, double hb, double hc, GridPoint p) {
  const double d = static_cast<double>(cross(a, b, c));
  const double wb = static_cast<double>(cross(a, p, c)) / d;
  const double wc = static_cast<double>(cross(a, b, p)) / d;
  return ha + (hb - ha) * wb + (hc - ha) * wc;
}

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
      double worst = 0, lo = INFINITY, hi = -INFINITY;
      const int32_t r = d.size;
      const int32_t x0 = std::max(0, centre.x - r), x1 = std::min(2 * grid.n(), centre.x + r);
      const int32_t y0 = std::max(0, centre.y - r), y1 = std::min(grid.n(), centre.y + r);
      for (int32_t y = y0; y <= y1; ++y) {
        for (int32_t x = x0 + ((x0 + y) & 1); x <= x1; x += 2) {
          const int32_t dx = std::abs(x - centre.x), dy = std::abs(y - centre.y);
          if (d.kind != MarkKind::kDiagonal && dx + dy > r) continue;
          const GridPoint p{x, y};
          const int64_t side = cross(e0, e1, p);
          // The triangle holding p; points on the hypotenuse take either.
          const bool first = side == 0 ? grid.inside(d.apexes[0]) : (side > 0) == (side0 > 0);
          const GridPoint a = first ? d.apexes[0] : d.apexes[1];
          const double v = fm[grid.id(p)];
          const double interp = plane(a, e0, e1, fm[grid.id(a)], h0, h1, p);
          worst = std::max(worst, std::abs(interp - v));
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
