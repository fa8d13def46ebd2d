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

uint8_t MarkGrid::sides(GridPoint p) const {
  uint8_t s = 0;
  if (p.x == 0) s |= kWest;
  if (p.x == 2 * n_) s |= kEast;
  if (p.y == 0) s |= kNorth;
  if (p.y == n_) s |= kSouth;
  return s;
}

int MarkGrid::class_of(const Diamond& d) {
  const int j = std::countr_zero(static_cast<uint32_t>(d.size));
  return d.kind == MarkKind::kDiagonal ? 2 * j : 2 * j - 1;
}

}  // namespace relief::lod
