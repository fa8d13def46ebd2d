#include "edge_marks.h"

#include <bit>
#include <cassert>
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

MarkGrid::MarkGrid(int k) : k_(k), n_(1 << k) {
  // Class 2j: diagonals of h = 2^j, (n / h) x (n / 2h) of them; class 2j - 1:
  // axis diamonds of s = 2^j, (n / s) x (n / 2s + 1) with a horizontal
  // hypotenuse and (n / s + 1) x (n / 2s) with a vertical one.
  uint32_t total = 0;
  for (int c = 0; c <= 2 * k - 2; ++c) {
    offsets_[static_cast<size_t>(c)] = total;
    const uint32_t n = static_cast<uint32_t>(n_);
    if (c % 2 == 0) {
      const uint32_t h = 1u << (c / 2);
      total += (n / h) * (n / (2 * h));
    } else {
      const uint32_t s = 1u << (c / 2 + 1);
      total += (n / s) * (n / (2 * s) + 1) + (n / s + 1) * (n / (2 * s));
    }
  }
  offsets_[static_cast<size_t>(2 * k - 1)] = total;
}

uint32_t MarkGrid::slot(GridPoint c) const {
  const int32_t bx = lowbit(c.x), by = lowbit(c.y);
  const uint32_t n = static_cast<uint32_t>(n_);
  const uint32_t x = static_cast<uint32_t>(c.x), y = static_cast<uint32_t>(c.y);
  if (bx == by) {  // a diagonal: both coordinates odd multiples of h
    const int j = std::countr_zero(static_cast<uint32_t>(bx));
    return offsets_[static_cast<size_t>(2 * j)] + (y >> (j + 1)) * (n >> j) + (x >> (j + 1));
  }
  const int32_t s = std::min(bx, by);
  const int j = std::countr_zero(static_cast<uint32_t>(s));
  assert(j >= 1 && "a sample's side: never split, no slot");
  const uint32_t first = offsets_[static_cast<size_t>(2 * j - 1)];
  if (bx < by) return first + (y >> (j + 1)) * (n >> j) + (x >> (j + 1));  // horizontal
  return first + ((n >> (j + 1)) + 1) * (n >> j) + (y >> (j + 1)) * ((n >> j) + 1) + (x >> (j + 1));
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
