#include "edge_marks.h"

#include <bit>
#include <cmath>

#include "relief/lod/mesh_topology.h"

namespace relief::lod {

double Diamond::hypotenuse() const {
  return kind == MarkKind::kDiagonal ? 2 * std::sqrt(2.0) * size : 2.0 * size;
}

std::array<GridPoint, 4> Diamond::children(GridPoint) const {
  std::array<GridPoint, 4> out;
  int i = 0;
  for (const GridPoint& e : ends) {
    for (const GridPoint& a : apexes) out[i++] = {(e.x + a.x) / 2, (e.y + a.y) / 2};
  }
  return out;
}

uint8_t MarkGrid::sides(GridPoint p) const {
  uint8_t s = 0;
  if (p.x == 0) s |= kWest;
  if (p.x == 2 * n_) s |= kEast;
  if (p.y == 0) s |= kNorth;
  if (p.y == n_) s |= kSouth;
  return s;
}

Diamond MarkGrid::diamond(GridPoint c) const {
  Diamond d;
  const int32_t bx = lowbit(c.x), by = lowbit(c.y);
  if (bx >= n_ && by >= n_) return d;  // a corner of a half: a vertex
  if (bx == by) {
    const int32_t h = bx;
    d.kind = MarkKind::kDiagonal;
    d.size = h;
    const GridPoint lo{c.x - h, c.y - h}, hi{c.x + h, c.y + h};
    const GridPoint a{c.x + h, c.y - h}, b{c.x - h, c.y + h};
    if (((lo.x + lo.y) / (2 * h)) % 2 == 0) {
      d.ends = {lo, hi};
      d.apexes = {a, b};
    } else {
      d.ends = {a, b};
      d.apexes = {lo, hi};
    }
    return d;
  }
  const int32_t s = std::min(bx, by);
  d.size = s;
  if (bx < by) {
    d.kind = MarkKind::kAxisX;
    d.ends = {GridPoint{c.x - s, c.y}, GridPoint{c.x + s, c.y}};
    d.apexes = {GridPoint{c.x, c.y - s}, GridPoint{c.x, c.y + s}};
  } else {
    d.kind = MarkKind::kAxisY;
    d.ends = {GridPoint{c.x, c.y - s}, GridPoint{c.x, c.y + s}};
    d.apexes = {GridPoint{c.x - s, c.y}, GridPoint{c.x + s, c.y}};
  }
  return d;
}

int MarkGrid::class_of(const Diamond& d) {
  const int j = std::countr_zero(static_cast<uint32_t>(d.size));
  return d.kind == MarkKind::kDiagonal ? 2 * j : 2 * j - 1;
}

}  // namespace relief::lod
