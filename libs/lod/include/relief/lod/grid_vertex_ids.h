#pragma once
// The ids of a refined mesh's grid vertices (refined_mesh.h), in the order a
// software rasteriser's vertex cache wants them.
#include <cstdint>
#include <vector>

namespace relief::lod {

// Grid vertex ids: the Morton (Z-order) code of (i, j) in each half of the
// grid (two squares of 2^k x 2^k cells, west then east), then the east
// column and the south row, and within every complete block of 256 ids the
// low 8 bits xor-ed with a hash of the block: a bijection onto 0 .. columns
// x rows - 1. Why: a software rasteriser shades a vertex again at every miss
// of its vertex cache, and Mesa's draw module (llvmpipe) keys a direct-mapped
// cache of 256 entries by the id modulo 256, cleared every 1023 indices. Row
// by row, with 2^(k+1) + 1 columns, a grid's anti-diagonals share their ids
// modulo 256 and llvmpipe shaded 1.8 vertices per triangle; with these ids
// any aligned block of 16 x 16 vertices fills the cache without a collision,
// the vertices of large triangles (a coarse lattice, Z-order codes that are
// multiples of 4^m) spread over it, and llvmpipe shades 0.6 (docs/rendering.md,
// "Vertex ids").
namespace grid_ids {
// The bits of v (< 2^16) moved to the even bits, and back.
constexpr uint32_t spread(uint32_t v) {
  v = (v | v << 8) & 0x00ff00ffu;
  v = (v | v << 4) & 0x0f0f0f0fu;
  v = (v | v << 2) & 0x33333333u;
  return (v | v << 1) & 0x55555555u;
}
constexpr uint32_t gather(uint32_t v) {
  v &= 0x55555555u;
  v = (v | v >> 1) & 0x33333333u;
  v = (v | v >> 2) & 0x0f0f0f0fu;
  v = (v | v >> 4) & 0x00ff00ffu;
  return (v | v >> 8) & 0x0000ffffu;
}

// The low 8 bits of an id in a complete block of 256 ids (of `count`)
// xor-ed with a hash of its block: its own inverse, a permutation within each
// block. Z-order alone gives the points of a coarse lattice (the vertices of
// large triangles) ids that are multiples of 4^m, one slot of the cache.
constexpr uint32_t scramble(uint32_t id, uint32_t count) {
  if ((id >> 8) >= (count >> 8)) return id;
  return id ^ (((id >> 8) * 0x9e3779b1u) >> 24);
}
// The Z-order code of a core vertex (i < 2^(k+1), j < 2^k) is a column's
// bits or-ed with a row's.
constexpr uint32_t column_bits(int k, uint32_t i) {
  return (i >> k) << (2 * k) | spread(i & ((1u << k) - 1));
}
constexpr uint32_t row_bits(uint32_t j) {
  return spread(j) << 1;
}
}  // namespace grid_ids

// Vertex (i, j) of the grid at level k (0 <= k <= 15).
constexpr uint32_t grid_vertex_id(int k, uint32_t i, uint32_t j) {
  const uint32_t n = 1u << k, core = 2 * n * n, count = (2 * n + 1) * (n + 1);
  uint32_t id = 0;
  if (i < 2 * n && j < n) {
    id = grid_ids::column_bits(k, i) | grid_ids::row_bits(j);
  } else {
    id = i == 2 * n ? core + j : core + n + 1 + i;  // the east column, else the south row
  }
  return grid_ids::scramble(id, count);
}

struct GridVertexPosition {
  uint32_t i = 0, j = 0;
};

constexpr GridVertexPosition grid_vertex_position(int k, uint32_t scrambled) {
  const uint32_t n = 1u << k, core = 2 * n * n;
  const uint32_t id = grid_ids::scramble(scrambled, (2 * n + 1) * (n + 1));
  if (id < core) {
    const uint32_t z = id & (n * n - 1);
    return {(id >> (2 * k)) << k | grid_ids::gather(z), grid_ids::gather(z >> 1)};
  }
  if (id <= core + n) return {2 * n, id - core};
  return {id - core - n - 1, n};
}

// grid_vertex_id(k, ...) for many vertices (refinement emits three per
// triangle): the Z-order code is a column's bits or-ed with a row's, looked
// up in two small tables.
class GridVertexIds {
 public:
  explicit GridVertexIds(int k) : k_(k), count_(((2u << k) + 1) * ((1u << k) + 1)) {
    const uint32_t n = 1u << k;
    for (uint32_t i = 0; i < 2 * n; ++i) {
      columns_.push_back(grid_ids::column_bits(k, i));
    }
    columns_.push_back(kEdge);
    for (uint32_t j = 0; j < n; ++j) rows_.push_back(grid_ids::row_bits(j));
    rows_.push_back(kEdge);
  }
  uint32_t operator()(uint32_t i, uint32_t j) const {
    const uint32_t z = columns_[i] | rows_[j];
    return z & kEdge ? grid_vertex_id(k_, i, j) : grid_ids::scramble(z, count_);
  }

 private:
  static constexpr uint32_t kEdge = 1u << 31;  // the east column or the south row
  int k_;
  uint32_t count_;
  std::vector<uint32_t> columns_, rows_;
};

}  // namespace relief::lod
