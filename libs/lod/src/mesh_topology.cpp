#include "relief/lod/mesh_topology.h"

#include <cassert>
#include <utility>

namespace relief::lod {

namespace {
int side_index(int side) {
  return side == kWest ? 0 : side == kEast ? 1 : side == kNorth ? 2 : 3;
}
}  // namespace

uint32_t MeshTopology::corner_vertex(int i, int j) const {
  return static_cast<uint32_t>(j * (squares_x() + 1) + i);
}
uint32_t MeshTopology::centre_vertex(int i, int j) const {
  return centre_base_ + static_cast<uint32_t>(j * squares_x() + i);
}
uint32_t MeshTopology::side_midpoint(int side, int k) const {
  return midpoint_base_[side_index(side)] + static_cast<uint32_t>(k);
}

MeshTopology::MeshTopology(int refinement) : refinement_(refinement) {
  assert(refinement >= 0 && refinement <= 10);
  const int nx = squares_x(), ny = squares_y();
  auto sides_of = [&](int i2, int j2) {  // doubled grid coordinates
    uint8_t s = 0;
    if (i2 == 0) s |= kWest;
    if (i2 == 2 * nx) s |= kEast;
    if (j2 == 0) s |= kNorth;
    if (j2 == 2 * ny) s |= kSouth;
    return s;
  };
  auto corner_of = [](uint8_t s) -> uint8_t {
    if ((s & kNorth) && (s & kWest)) return kNorthWest;
    if ((s & kNorth) && (s & kEast)) return kNorthEast;
    if ((s & kSouth) && (s & kWest)) return kSouthWest;
    if ((s & kSouth) && (s & kEast)) return kSouthEast;
    return 0;
  };
  auto add = [&](int i2, int j2) {
    const uint8_t s = sides_of(i2, j2);
    vertices_.push_back({static_cast<float>(i2) / static_cast<float>(2 * nx),
                         static_cast<float>(j2) / static_cast<float>(2 * ny), s, corner_of(s)});
  };
  for (int j = 0; j <= ny; ++j) {
    for (int i = 0; i <= nx; ++i) add(2 * i, 2 * j);
  }
  centre_base_ = static_cast<uint32_t>(vertices_.size());
  for (int j = 0; j < ny; ++j) {
    for (int i = 0; i < nx; ++i) add(2 * i + 1, 2 * j + 1);
  }
  midpoint_base_[0] = static_cast<uint32_t>(vertices_.size());
  for (int j = 0; j < ny; ++j) add(0, 2 * j + 1);
  midpoint_base_[1] = static_cast<uint32_t>(vertices_.size());
  for (int j = 0; j < ny; ++j) add(2 * nx, 2 * j + 1);
  midpoint_base_[2] = static_cast<uint32_t>(vertices_.size());
  for (int i = 0; i < nx; ++i) add(2 * i + 1, 0);
  midpoint_base_[3] = static_cast<uint32_t>(vertices_.size());
  for (int i = 0; i < nx; ++i) add(2 * i + 1, 2 * ny);

  // Counter-clockwise seen from above: in (u, -v), east right and north up.
  auto emit = [&](std::vector<uint32_t>& out, uint32_t a, uint32_t b, uint32_t c) {
    const MeshVertex &pa = vertices_[a], &pb = vertices_[b], &pc = vertices_[c];
    const double area = (pb.u - pa.u) * (-(pc.v - pa.v)) - (-(pb.v - pa.v)) * (pc.u - pa.u);
    if (area < 0) std::swap(b, c);
    out.insert(out.end(), {a, b, c});
  };
  // Triangles of square (i, j): one per square edge, with the centre.
  std::vector<uint32_t> core, border[4][2];  // border[side][split]
  for (int j = 0; j < ny; ++j) {
    for (int i = 0; i < nx; ++i) {
      const uint32_t c = centre_vertex(i, j);
      const uint32_t nw = corner_vertex(i, j), ne = corner_vertex(i + 1, j),
                     sw = corner_vertex(i, j + 1), se = corner_vertex(i + 1, j + 1);
      struct Edge {
        uint32_t a, b;
        int side;  // 0 when not on the quad border
        int k;
      };
      const Edge edges[4] = {{nw, ne, j == 0 ? kNorth : 0, i},
                             {ne, se, i == nx - 1 ? kEast : 0, j},
                             {se, sw, j == ny - 1 ? kSouth : 0, i},
                             {sw, nw, i == 0 ? kWest : 0, j}};
      for (const Edge& e : edges) {
        if (!e.side) {
          emit(core, c, e.a, e.b);
          continue;
        }
        const int s = side_index(e.side);
        emit(border[s][0], c, e.a, e.b);
        const uint32_t m = side_midpoint(e.side, e.k);
        emit(border[s][1], c, e.a, m);
        emit(border[s][1], c, m, e.b);
      }
    }
  }
  for (int mask = 0; mask < 16; ++mask) {
    first_[mask] = static_cast<uint32_t>(indices_.size());
    indices_.insert(indices_.end(), core.begin(), core.end());
    const int bits[4] = {kWest, kEast, kNorth, kSouth};
    for (int s = 0; s < 4; ++s) {
      const auto& part = border[s][(mask & bits[s]) ? 1 : 0];
      indices_.insert(indices_.end(), part.begin(), part.end());
    }
    count_[mask] = static_cast<uint32_t>(indices_.size()) - first_[mask];
  }
}

}  // namespace relief::lod
