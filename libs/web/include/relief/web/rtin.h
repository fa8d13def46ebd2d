#pragma once
// A right-triangulated irregular network (RTIN) over a (2^k + 1)^2 lattice:
// the longest-edge-bisection hierarchy that edge-mark refinement walks
// (seed 003), in the array form of Mapbox's Martini. Each point that is the
// midpoint of some triangle's hypotenuse carries an error: the largest
// vertical distance between the lattice and the planes of the triangles
// that leave it out (every lattice point inside them, not only the midpoint
// Martini measures), taken over its whole subtree, so a parent's error is
// never below its children's. Cutting at one threshold then gives a conforming mesh: the
// point is a vertex exactly when its error exceeds the threshold.
//
// Lattice coordinates: x east, y south (row 0 is the north edge), point
// (x, y) at index y * size + x.
#include <cstdint>
#include <span>
#include <vector>

namespace relief::web {

struct RtinMesh {
  // Lattice coordinates (x, y) of each vertex, numbered by first use in
  // `triangles`.
  std::vector<uint16_t> xy;
  // Three vertex indices per triangle, counter-clockwise with x east and y
  // south as drawn on a map (clockwise in the lattice's own axes).
  std::vector<uint32_t> triangles;
  size_t vertex_count() const { return xy.size() / 2; }
  size_t triangle_count() const { return triangles.size() / 3; }
};

class Rtin {
 public:
  explicit Rtin(int log2_cells = 8);
  int size() const { return size_; }  // points per side: 2^k + 1

  // Accumulates the errors of `heights` (size^2, finite) into `errors`
  // (size^2): each midpoint's error becomes the largest of what it held and
  // what its triangles measure here. Start from zeros for a lattice alone;
  // values preset on the boundary (a neighbour's errors there) carry into
  // every triangle above them, which is how two tiles agree on the vertices
  // of their shared edge.
  void accumulate_errors(std::span<const float> heights, std::span<float> errors) const;

  // Carries raised errors (a neighbour's, preset on the boundary of errors
  // already accumulated) up to every triangle above them: the same result
  // as accumulating over the raised errors, without measuring again.
  void propagate_errors(std::span<float> errors) const;

  // The conforming mesh keeping every point whose error exceeds max_error.
  RtinMesh mesh(std::span<const float> errors, float max_error) const;

 private:
  int size_;
  // Per triangle of the hierarchy (all but the 2 roots), finest first from
  // the back: the hypotenuse's ends a and b as (ax, ay, bx, by).
  std::vector<uint16_t> coords_;
  size_t parent_triangles_ = 0;
};

}  // namespace relief::web
