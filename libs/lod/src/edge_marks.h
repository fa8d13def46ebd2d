#pragma once
// The edge-mark grid of one quad (seed 003 §3.3.3), for refinement.
//
// The quad's refinement grid has 2n x n cells, n = 2^k, half a data sample
// each: grid point (x, y), 0 <= x <= 2n, 0 <= y <= n (x east, y south); odd
// points are sample centres, even ones sample corners. The quad is two
// squares (halves) of n x n cells, [0, n] and [n, 2n], each refined as a 4-8
// mesh: every grid point that is not a half's corner is the centre of exactly
// one diamond (a pair of right isosceles triangles sharing a hypotenuse), the
// point being the hypotenuse's midpoint: its edge mark. Splitting a diamond
// adds its centre as a vertex and makes four triangles out of two.
//
// - Axis diamonds: a horizontal (kAxisX) or vertical (kAxisY) hypotenuse of
//   half-length s, end points centre -+ s along it, apexes -+ s across.
// - Diagonal diamonds: an axis-aligned square of half-side h; the hypotenuse is
//   the diagonal whose end points have (x + y) / 2h even.
// The children of a diamond are centred at the midpoints of its four legs
// (end point to apex), its two parents at its apexes. Each half's centre is a
// diagonal diamond of h = n / 2 that is always split (the coarsest mesh: four
// triangles around it); level 0 are the half's sides. The finest diamonds
// worth splitting are the sample cells (h = 1, which adds the sample centre);
// axis diamonds of s = 1 (a sample's side) are never split, so the finest
// triangulation is the full mesh of the level: every sample cell cut by its
// two diagonals.
#include <algorithm>
#include <array>
#include <bit>
#include <cassert>
#include <cstdint>

namespace relief::lod {

struct GridPoint {
  int32_t x = 0, y = 0;
};

enum class MarkKind : uint8_t { kVertex, kAxisX, kAxisY, kDiagonal };

struct Diamond {
  MarkKind kind = MarkKind::kVertex;
  int32_t size = 0;                 // s (axis) or h (diagonal)
  std::array<GridPoint, 2> ends;    // the hypotenuse
  std::array<GridPoint, 2> apexes;  // may lie outside the quad (border diamonds)

  // Radius (grid cells, max norm) around the centre of a square holding the
  // diamond and all of its descendants, nested in its parents': 2s or 3h.
  int32_t reach() const { return kind == MarkKind::kDiagonal ? 3 * size : 2 * size; }
  // Length of the hypotenuse in grid cells.
  double hypotenuse() const;
  std::array<GridPoint, 4> children(GridPoint centre) const;
};

class MarkGrid {
 public:
  explicit MarkGrid(int k);
  int k() const { return k_; }
  int32_t n() const { return n_; }
  int32_t columns() const { return 2 * n_ + 1; }
  int32_t rows() const { return n_ + 1; }
  uint32_t count() const { return static_cast<uint32_t>(columns()) * rows(); }
  uint32_t id(GridPoint p) const { return static_cast<uint32_t>(p.y * columns() + p.x); }
  bool inside(GridPoint p) const { return p.x >= 0 && p.x <= 2 * n_ && p.y >= 0 && p.y <= n_; }
  // A corner of a half (x = 0, n, 2n; y = 0, n), inside the grid: the only vertices.
  bool is_corner(GridPoint p) const { return ((p.x | p.y) & (n_ - 1)) == 0; }
  // Side bits (mesh_topology.h) of the quad sides the point lies on.
  uint8_t sides(GridPoint p) const;

  Diamond diamond(GridPoint centre) const;
  // A diamond that may ever be split: not a vertex, not a sample's side.
  static bool splittable(const Diamond& d) {
    return d.kind == MarkKind::kDiagonal ? d.size >= 1 : d.kind != MarkKind::kVertex && d.size >= 2;
  }
  bool is_root(const Diamond& d) const { return d.kind == MarkKind::kDiagonal && d.size == n_ / 2; }

  // Classes of diamonds from the finest to the coarsest, roots excluded:
  // class 2j holds the diagonals of h = 2^j, class 2j + 1 the axis diamonds of
  // s = 2^(j + 1); the last (2k - 3) are the halves' sides (level 0).
  int classes() const { return 2 * k_ - 2; }
  template <class F>
  void for_each_in_class(int c, F f) const {
    const int32_t size = int32_t{1} << (c / 2);
    if (c % 2 == 0) {  // diagonals: both coordinates odd multiples of h
      for (int32_t y = size; y < n_; y += 2 * size) {
        for (int32_t x = size; x < 2 * n_; x += 2 * size) {
          f(GridPoint{x, y});
        }
      }
      return;
    }
    const int32_t s = 2 * size;  // axis: one coordinate an odd multiple of s, the other of 2s
    for (int32_t y = 0; y <= n_; y += 2 * s) {
      for (int32_t x = s; x < 2 * n_; x += 2 * s) f(GridPoint{x, y});
    }
    for (int32_t y = s; y < n_; y += 2 * s) {
      for (int32_t x = 0; x <= 2 * n_; x += 2 * s) f(GridPoint{x, y});
    }
  }
  // The class of a splittable, non-root diamond.
  static int class_of(const Diamond& d);

  // Diamonds numbered class by class (the roots last), in row order within
  // a class: what is stored per diamond, so that the coarse diamonds every
  // frame visits first lie together in memory instead of one per grid row.
  uint32_t slots() const { return offsets_[2 * k_ - 1]; }
  // The first slot of class c (0 <= c <= classes(): then the halves' centres).
  uint32_t class_offset(int c) const { return offsets_[static_cast<size_t>(c)]; }
  uint32_t slot(GridPoint centre) const;
  // slot() where the diamond's kind and size are known (2^j: h of a
  // diagonal, s of an axis diamond): the same numbers, without finding them.
  uint32_t diagonal_slot(int j, GridPoint c) const {
    return offsets_[static_cast<size_t>(2 * j)] +
           (static_cast<uint32_t>(c.y) >> (j + 1)) * (static_cast<uint32_t>(n_) >> j) +
           (static_cast<uint32_t>(c.x) >> (j + 1));
  }
  uint32_t axis_slot(int j, GridPoint c, bool horizontal) const {
    const uint32_t n = static_cast<uint32_t>(n_);
    const uint32_t x = static_cast<uint32_t>(c.x), y = static_cast<uint32_t>(c.y);
    const uint32_t first = offsets_[static_cast<size_t>(2 * j - 1)];
    if (horizontal) return first + (y >> (j + 1)) * (n >> j) + (x >> (j + 1));
    return first + ((n >> (j + 1)) + 1) * (n >> j) + (y >> (j + 1)) * ((n >> j) + 1) +
           (x >> (j + 1));
  }

 private:
  int32_t lowbit(int32_t v) const { return v == 0 ? 4 * n_ : v & -v; }
  int k_;
  int32_t n_;
  std::array<uint32_t, 64> offsets_{};  // the first slot of each class
};

// Inline: refinement calls both several times per diamond.
inline Diamond MarkGrid::diamond(GridPoint c) const {
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

inline uint32_t MarkGrid::slot(GridPoint c) const {
  const int32_t bx = lowbit(c.x), by = lowbit(c.y);
  if (bx == by) {  // a diagonal: both coordinates odd multiples of h
    return diagonal_slot(std::countr_zero(static_cast<uint32_t>(bx)), c);
  }
  const int32_t s = std::min(bx, by);
  const int j = std::countr_zero(static_cast<uint32_t>(s));
  assert(j >= 1 && "a sample's side: never split, no slot");
  return axis_slot(j, c, bx < by);
}

}  // namespace relief::lod
