#pragma once
// The conforming triangulation of one quad at refinement level r (seed 003
// §1.4.3): the quad is divided into 2^(r+1) x 2^r squares, each cut by its two
// diagonals into four right-angled isosceles triangles around a centre vertex.
// A triangle whose hypotenuse lies on a side shared with a finer neighbour is
// split at the hypotenuse's midpoint, so the two meshes meet vertex to vertex:
// no T-junctions. The core is the same for every quad; the border comes in 16
// variants, one per combination of finer sides.
//
// Quad space: u in [0, 1] from west to east, v in [0, 1] from north to south.
#include <cstddef>
#include <cstdint>
#include <vector>

namespace relief::lod {

enum Side : uint8_t { kWest = 1, kEast = 2, kNorth = 4, kSouth = 8 };
enum Corner : uint8_t { kNorthWest = 1, kNorthEast = 2, kSouthWest = 4, kSouthEast = 8 };

struct MeshVertex {
  float u = 0, v = 0;
  uint8_t sides = 0;   // Side bits of the quad sides the vertex lies on
  uint8_t corner = 0;  // Corner bit when the vertex is a quad corner
};

class MeshTopology {
 public:
  explicit MeshTopology(int refinement);
  int refinement() const { return refinement_; }
  int squares_x() const { return 2 << refinement_; }
  int squares_y() const { return 1 << refinement_; }
  const std::vector<MeshVertex>& vertices() const { return vertices_; }
  // All 16 variants' triangles in one index array; `finer_sides` is a mask of Side bits.
  const std::vector<uint32_t>& indices() const { return indices_; }
  uint32_t first_index(int finer_sides) const { return first_[finer_sides]; }
  uint32_t index_count(int finer_sides) const { return count_[finer_sides]; }
  size_t triangle_count(int finer_sides) const { return count_[finer_sides] / 3; }

  // Vertex ids, for evaluation on the CPU.
  uint32_t corner_vertex(int i, int j) const;     // grid corner (i, j), 0 <= i <= squares_x
  uint32_t centre_vertex(int i, int j) const;     // centre of square (i, j)
  uint32_t side_midpoint(int side, int k) const;  // midpoint of the k-th square edge on a side

 private:
  int refinement_;
  std::vector<MeshVertex> vertices_;
  std::vector<uint32_t> indices_;
  uint32_t first_[16] = {}, count_[16] = {};
  uint32_t centre_base_ = 0, midpoint_base_[4] = {};
};

}  // namespace relief::lod
