#include "diamond_errors.h"

#include <algorithm>
#include <cmath>
#if defined(__SSE2__)
#include <emmintrin.h>
#endif

#include "relief/lod/data_window.h"

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

// The largest |plane - full mesh| over the full-mesh vertices (x + y even)
// of row y from x = from to x = to; `last`: the row's last index (x = 2n).
inline double row_error(const TrianglePlane& plane, const float* row, int32_t y, int32_t from,
                        int32_t to, int32_t last) {
  const double base = plane.ha + plane.gy * (y - plane.a.y);
  int32_t x = from + ((from + y) & 1);
  double worst = 0;
#if defined(__SSE2__)
  // Four vertices a step (x, x + 2, x + 4, x + 6: eight floats read, every
  // other kept), two per register, each with the scalar loop's arithmetic
  // in the same order: the same values, so the same maximum. Most of the
  // measuring's time is here (the loaders prepare every elevation tile).
  if (x + 6 <= to && x + 7 <= last) {
    const __m128d gx = _mm_set1_pd(plane.gx), b = _mm_set1_pd(base), sign = _mm_set1_pd(-0.0);
    const __m128d step = _mm_set1_pd(8);
    const double d = x - plane.a.x;  // exact in a double, as are d + 2 .. d + 6
    __m128d x0 = _mm_set_pd(d + 2, d), x1 = _mm_set_pd(d + 6, d + 4);
    __m128d w0 = _mm_setzero_pd(), w1 = _mm_setzero_pd();
    for (; x + 6 <= to && x + 7 <= last; x += 8) {
      const __m128 lo = _mm_loadu_ps(row + x), hi = _mm_loadu_ps(row + x + 4);
      const __m128 kept = _mm_shuffle_ps(lo, hi, _MM_SHUFFLE(2, 0, 2, 0));
      const __m128d h0 = _mm_cvtps_pd(kept), h1 = _mm_cvtps_pd(_mm_movehl_ps(kept, kept));
      w0 = _mm_max_pd(w0, _mm_andnot_pd(sign, _mm_sub_pd(_mm_add_pd(b, _mm_mul_pd(gx, x0)), h0)));
      w1 = _mm_max_pd(w1, _mm_andnot_pd(sign, _mm_sub_pd(_mm_add_pd(b, _mm_mul_pd(gx, x1)), h1)));
      x0 = _mm_add_pd(x0, step);
      x1 = _mm_add_pd(x1, step);
    }
    const __m128d w = _mm_max_pd(w0, w1);
    worst = std::max(_mm_cvtsd_f64(w), _mm_cvtsd_f64(_mm_unpackhi_pd(w, w)));
  }
#else
  (void)last;
#endif
  for (; x <= to; x += 2)
    worst = std::max(worst, std::abs(base + plane.gx * (x - plane.a.x) - row[x]));
  return worst;
}

// max |D's two triangles - full mesh| over the full mesh's vertices in
// diamond d of centre c (the part inside the grid). A point belongs to the
// triangle on its side of the hypotenuse (on it, to the first if that one is
// inside the grid); rows are cut where the hypotenuse crosses them instead
// of testing every point.
double diamond_error(const MarkGrid& grid, const std::vector<float>& fm, GridPoint c,
                     const Diamond& d) {
  const GridPoint e0 = d.ends[0], e1 = d.ends[1];
  const double h0 = fm[grid.id(e0)], h1 = fm[grid.id(e1)];
  const int64_t side0 = cross(e0, e1, d.apexes[0]);
  // The triangles' planes (an apex outside the grid: never used).
  auto plane_of = [&](GridPoint a) {
    return grid.inside(a) ? TrianglePlane(a, e0, e1, fm[grid.id(a)], h0, h1)
                          : TrianglePlane(e0, e1, a, h0, h1, 0);
  };
  const TrianglePlane planes[2] = {plane_of(d.apexes[0]), plane_of(d.apexes[1])};
  const TrianglePlane& on_line = planes[grid.inside(d.apexes[0]) ? 0 : 1];
  // The plane of the points strictly on p's side of the hypotenuse.
  auto side_of = [&](GridPoint p) -> const TrianglePlane& {
    return (cross(e0, e1, p) > 0) == (side0 > 0) ? planes[0] : planes[1];
  };
  // The hypotenuse is a straight line: the points before it in a row (or,
  // for a horizontal one, the rows above it) are all on one side.
  const bool horizontal = d.kind == MarkKind::kAxisX;
  const TrianglePlane& before =
      side_of(horizontal ? GridPoint{c.x, c.y - 1} : GridPoint{c.x - 1, c.y});
  const TrianglePlane& after =
      side_of(horizontal ? GridPoint{c.x, c.y + 1} : GridPoint{c.x + 1, c.y});
  const int32_t r = d.size;
  const int32_t last = 2 * grid.n();
  const int32_t x0 = std::max(0, c.x - r), x1 = std::min(last, c.x + r);
  const int32_t y0 = std::max(0, c.y - r), y1 = std::min(grid.n(), c.y + r);
  const bool diagonal = d.kind == MarkKind::kDiagonal;
  // Diagonals: the hypotenuse runs along x - c.x = y - c.y, or = c.y - y.
  const bool main_diagonal = (e1.x - e0.x) * (e1.y - e0.y) > 0;
  double worst = 0;
  for (int32_t y = y0; y <= y1; ++y) {
    const int32_t dy = y - c.y;
    // Axis diamonds: the points within L1 distance r of the centre.
    const int32_t reach = diagonal ? r : r - std::abs(dy);
    const int32_t xa = std::max(x0, c.x - reach), xb = std::min(x1, c.x + reach);
    const float* row = &fm[grid.id({0, y})];
    if (horizontal) {  // a row wholly on one side, or the hypotenuse
      worst = std::max(worst, row_error(dy == 0  ? on_line
                                        : dy < 0 ? before
                                                 : after,
                                        row, y, xa, xb, last));
      continue;
    }
    const int32_t xc = !diagonal ? c.x : main_diagonal ? c.x + dy : c.x - dy;
    if (xa < xc) worst = std::max(worst, row_error(before, row, y, xa, std::min(xb, xc - 1), last));
    if (xa <= xc && xc <= xb && ((xc + y) & 1) == 0) {
      worst = std::max(worst, std::abs(on_line.at(xc, y) - row[xc]));
    }
    if (xb > xc) worst = std::max(worst, row_error(after, row, y, std::max(xa, xc + 1), xb, last));
  }
  return worst;
}

// diamond_error of an axis diamond of s = 2 in closed form: its full-mesh
// vertices are its centre, the ends and apexes (the triangles' vertices) and
// the midpoints of its legs, where the triangles are the legs' means.
double small_axis_error(const MarkGrid& grid, const std::vector<float>& fm, GridPoint c,
                        const Diamond& d) {
  auto at = [&](GridPoint p) { return double{fm[grid.id(p)]}; };
  double worst = std::abs(0.5 * (at(d.ends[0]) + at(d.ends[1])) - at(c));
  for (const GridPoint& a : d.apexes) {
    if (!grid.inside(a)) continue;
    for (const GridPoint& e : d.ends) {
      const GridPoint m{(a.x + e.x) / 2, (a.y + e.y) / 2};
      worst = std::max(worst, std::abs(0.5 * (at(e) + at(a)) - at(m)));
    }
  }
  return worst;
}

float round_up(double v) {
  float f = static_cast<float>(v);
  if (static_cast<double>(f) < v) f = std::nextafter(f, INFINITY);
  return f;
}

// The full mesh's heights at its vertices: points with x + y even (sample
// centres and corners), the bilinear interpolation of the vertex shader.
// Into `fm` (grid.count() values; the others are not written).
void full_mesh_heights(const MarkGrid& grid, const tiles::Raster& tile, int border,
                       std::vector<float>& fm) {
  fm.resize(grid.count());
  const int32_t n = grid.n();
  if (border < 1 || tile.width() < n + 2 * border || tile.height() < n / 2 + 2 * border) {
    for (int32_t y = 0; y <= n; ++y) {
      for (int32_t x = y % 2; x <= 2 * n; x += 2) {
        fm[grid.id({x, y})] = bilinear_height(tile, border, x / 2.0, y / 2.0);
      }
    }
    return;
  }
  // bilinear_height()'s arithmetic where it needs no clamping (a border
  // of at least one sample): a sample centre (x, y odd) is the sample, a
  // corner (x, y even) its four samples' weights of one half.
  const int w = tile.width();
  const float* v = tile.f32().data();
  for (int32_t y = 0; y <= n; ++y) {
    float* out = &fm[grid.id({0, y})];
    if (y % 2) {
      const float* row = v + static_cast<size_t>(y / 2 + border) * w + border;
      for (int32_t x = 1; x <= 2 * n; x += 2) out[x] = row[x / 2];
      continue;
    }
    const float* top = v + static_cast<size_t>(y / 2 + border - 1) * w + border - 1;
    const float* bottom = top + w;
    for (int32_t x = 0; x <= 2 * n; x += 2) {
      const int32_t i = x / 2;
      const float t = top[i] + (top[i + 1] - top[i]) * 0.5f;
      const float b = bottom[i] + (bottom[i + 1] - bottom[i]) * 0.5f;
      out[x] = t + (b - t) * 0.5f;
    }
  }
}

}  // namespace

DiamondErrors measure_diamonds(const MarkGrid& grid, const tiles::Raster& tile, int border) {
  // Reused per thread: the loaders measure tile after tile, and a fresh 2 MB
  // buffer each time costs its page faults again.
  thread_local std::vector<float> fm;
  full_mesh_heights(grid, tile, border, fm);
  DiamondErrors out;
  out.at.resize(grid.slots());  // every slot written below
  // The roots (the halves' diagonals), always split: never read, but defined.
  out.at[grid.slot({grid.n() / 2, grid.n() / 2})] = DiamondError{};
  out.at[grid.slot({3 * grid.n() / 2, grid.n() / 2})] = DiamondError{};
  // The finest diamonds (class 0, a sample cell around its centre): the
  // cell's corners are the triangles' vertices, so the error is the centre's
  // distance to the diagonal's midpoint; the heights are the five points'.
  // Row by row (MarkGrid::diamond's and slot()'s arithmetic for h = 1: the
  // centres are the odd points, their slots consecutive).
  const int32_t n = grid.n(), columns = grid.columns();
  DiamondError* slot = out.at.data() + grid.slot({1, 1});
  for (int32_t y = 1; y < n; y += 2) {
    for (int32_t x = 1; x < 2 * n; x += 2, ++slot) {
      const float* centre = &fm[grid.id({x, y})];
      const float nw = centre[-columns - 1], ne = centre[-columns + 1];
      const float sw = centre[columns - 1], se = centre[columns + 1];
      // The hypotenuse: north-west to south-east where (x - 1 + y - 1) / 2 is even.
      const bool main_diagonal = ((x + y - 2) / 2) % 2 == 0;
      const double mid =
          main_diagonal ? 0.5 * (double{nw} + double{se}) : 0.5 * (double{ne} + double{sw});
      slot->error = round_up(std::abs(mid - *centre));
      const float lo = std::min({*centre, nw, ne, sw, se}),
                  hi = std::max({*centre, nw, ne, sw, se});
      slot->lo = static_cast<int16_t>(std::clamp(std::floor(lo), -32768.0f, 32767.0f));
      slot->hi = static_cast<int16_t>(std::clamp(std::ceil(hi), -32768.0f, 32767.0f));
    }
  }
  for (int c = 1; c < grid.classes(); ++c) {
    grid.for_each_in_class(c, [&](GridPoint centre) {
      const Diamond d = grid.diamond(centre);
      float error = round_up(c == 1 ? small_axis_error(grid, fm, centre, d)
                                    : diamond_error(grid, fm, centre, d));
      // Saturated: the children (class c - 1) inside the grid. Their areas
      // cover the part of this diamond inside the grid (its two triangles, or
      // the inner one on the border, are their four, or two, triangles), so
      // the height range is theirs.
      // (Diamond::children(), with the slots from the class known: finding
      // each child's kind and size was a third of the measuring's time.)
      int16_t lo = INT16_MAX, hi = INT16_MIN;
      auto take = [&](GridPoint child, uint32_t cid) {
        if (!grid.inside(child)) return;
        error = std::max(error, out.at[cid].error);
        lo = std::min(lo, out.at[cid].lo);
        hi = std::max(hi, out.at[cid].hi);
      };
      const int32_t x = centre.x, y = centre.y;
      uint32_t own;
      if (c % 2 == 0) {  // a diagonal of h = 2^j: axis children of s = h on its sides
        const int j = c / 2;
        const int32_t h = int32_t{1} << j;
        for (const GridPoint child : {GridPoint{x, y - h}, GridPoint{x, y + h}}) {
          take(child, grid.axis_slot(j, child, true));
        }
        for (const GridPoint child : {GridPoint{x - h, y}, GridPoint{x + h, y}}) {
          take(child, grid.axis_slot(j, child, false));
        }
        own = grid.diagonal_slot(j, centre);
      } else {  // an axis diamond of s = 2^j: diagonal children of h = s / 2
        const int j = (c + 1) / 2;
        const int32_t h = int32_t{1} << (j - 1);
        for (const GridPoint child : {GridPoint{x - h, y - h}, GridPoint{x + h, y - h},
                                      GridPoint{x - h, y + h}, GridPoint{x + h, y + h}}) {
          take(child, grid.diagonal_slot(j - 1, child));
        }
        own = grid.axis_slot(j, centre, d.kind == MarkKind::kAxisX);
      }
      out.at[own] = {error, lo, hi};
    });
  }
  return out;
}

}  // namespace relief::lod
