#include "relief/web/rtin.h"

#include <algorithm>
#include <cassert>
#include <cmath>

namespace relief::web {

// Triangle ids follow the implicit binary tree of Martini: ids 2 and 3 are
// the two roots (the square cut along (0, 0)-(n, n)), child ids append one
// bit per bisection. Ids are enumerated coarse to fine, so walking the array
// backwards visits every child before its parent.
Rtin::Rtin(int log2_cells) : size_((1 << log2_cells) + 1) {
  assert(log2_cells >= 1 && log2_cells <= 15);
  const size_t n = static_cast<size_t>(size_ - 1);
  const size_t triangles = n * n * 2 - 2;
  parent_triangles_ = triangles - n * n;
  coords_.resize(triangles * 4);
  const int max = size_ - 1;
  for (size_t i = 0; i < triangles; ++i) {
    size_t id = i + 2;
    int ax = 0, ay = 0, bx = 0, by = 0, cx = 0, cy = 0;
    if (id & 1) {
      bx = by = cx = max;
    } else {
      ax = ay = cy = max;
    }
    while ((id >>= 1) > 1) {
      const int mx = (ax + bx) >> 1, my = (ay + by) >> 1;
      if (id & 1) {  // the half on a's side
        bx = ax, by = ay;
        ax = cx, ay = cy;
      } else {
        ax = bx, ay = by;
        bx = cx, by = cy;
      }
      cx = mx, cy = my;
    }
    coords_[i * 4 + 0] = static_cast<uint16_t>(ax);
    coords_[i * 4 + 1] = static_cast<uint16_t>(ay);
    coords_[i * 4 + 2] = static_cast<uint16_t>(bx);
    coords_[i * 4 + 3] = static_cast<uint16_t>(by);
  }
}

namespace {

// The largest |plane - lattice| over the lattice points of triangle (a, b, c):
// what leaving the triangle unsplit costs. Martini measures only the
// hypotenuse's midpoint, which errs by what deeper points add up to; this
// bound holds at every point of the tile.
float triangle_error(std::span<const float> h, size_t size, int ax, int ay, int bx, int by, int cx,
                     int cy) {
  const auto height = [&](int x, int y) {
    return double{h[static_cast<size_t>(y) * size + static_cast<size_t>(x)]};
  };
  const double ha = height(ax, ay);
  const double ux = bx - ax, uy = by - ay, vx = cx - ax, vy = cy - ay;
  const double det = ux * vy - uy * vx;
  const double db = height(bx, by) - ha, dc = height(cx, cy) - ha;
  const double gx = (db * vy - dc * uy) / det, gy = (dc * ux - db * vx) / det;
  const int x0 = std::min({ax, bx, cx}), x1 = std::max({ax, bx, cx});
  const int y0 = std::min({ay, by, cy}), y1 = std::max({ay, by, cy});
  // Inside: on the same side of all three edges as the opposite vertex. In
  // 64 bits: on a 257-point lattice a side is up to 2^16, and the products
  // of two sides below overflow an int (UBSan saw -65536 * -65536).
  const auto side = [](int px, int py, int qx, int qy, int x, int y) {
    return int64_t{qx - px} * (y - py) - int64_t{qy - py} * (x - px);
  };
  const int64_t sa = side(bx, by, cx, cy, ax, ay), sb = side(cx, cy, ax, ay, bx, by),
                sc = side(ax, ay, bx, by, cx, cy);
  double worst = 0;
  for (int y = y0; y <= y1; ++y) {
    for (int x = x0; x <= x1; ++x) {
      if (side(bx, by, cx, cy, x, y) * sa < 0 || side(cx, cy, ax, ay, x, y) * sb < 0 ||
          side(ax, ay, bx, by, x, y) * sc < 0) {
        continue;
      }
      const double plane = ha + gx * (x - ax) + gy * (y - ay);
      worst = std::max(worst, std::abs(plane - height(x, y)));
    }
  }
  return static_cast<float>(worst);
}

}  // namespace

void Rtin::accumulate_errors(std::span<const float> heights, std::span<float> errors) const {
  const size_t size = static_cast<size_t>(size_);
  assert(heights.size() == size * size && errors.size() == size * size);
  const size_t triangles = coords_.size() / 4;
  for (size_t i = triangles; i-- > 0;) {
    const int ax = coords_[i * 4], ay = coords_[i * 4 + 1];
    const int bx = coords_[i * 4 + 2], by = coords_[i * 4 + 3];
    const int mx = (ax + bx) >> 1, my = (ay + by) >> 1;
    const int cx = mx + my - ay, cy = my + ax - mx;  // the right angle
    const size_t m = static_cast<size_t>(my) * size + static_cast<size_t>(mx);
    float error = std::max(errors[m], triangle_error(heights, size, ax, ay, bx, by, cx, cy));
    if (i < parent_triangles_) {
      const size_t left =
          static_cast<size_t>((ay + cy) >> 1) * size + static_cast<size_t>((ax + cx) >> 1);
      const size_t right =
          static_cast<size_t>((by + cy) >> 1) * size + static_cast<size_t>((bx + cx) >> 1);
      error = std::max({error, errors[left], errors[right]});
    }
    errors[m] = error;
  }
}

void Rtin::propagate_errors(std::span<float> errors) const {
  const size_t size = static_cast<size_t>(size_);
  for (size_t i = parent_triangles_; i-- > 0;) {
    const int ax = coords_[i * 4], ay = coords_[i * 4 + 1];
    const int bx = coords_[i * 4 + 2], by = coords_[i * 4 + 3];
    const int mx = (ax + bx) >> 1, my = (ay + by) >> 1;
    const int cx = mx + my - ay, cy = my + ax - mx;
    const size_t m = static_cast<size_t>(my) * size + static_cast<size_t>(mx);
    const size_t left =
        static_cast<size_t>((ay + cy) >> 1) * size + static_cast<size_t>((ax + cx) >> 1);
    const size_t right =
        static_cast<size_t>((by + cy) >> 1) * size + static_cast<size_t>((bx + cx) >> 1);
    errors[m] = std::max({errors[m], errors[left], errors[right]});
  }
}

namespace {

struct MeshBuilder {
  std::span<const float> errors;
  float max_error;
  int size;
  std::vector<uint32_t> number;  // lattice index -> vertex number + 1
  RtinMesh mesh;

  uint32_t vertex(int x, int y) {
    uint32_t& n =
        number[static_cast<size_t>(y) * static_cast<size_t>(size) + static_cast<size_t>(x)];
    if (n == 0) {
      mesh.xy.push_back(static_cast<uint16_t>(x));
      mesh.xy.push_back(static_cast<uint16_t>(y));
      n = static_cast<uint32_t>(mesh.xy.size() / 2);
    }
    return n - 1;
  }

  // Triangle (a, b, c) with hypotenuse a-b and right angle c.
  void add(int ax, int ay, int bx, int by, int cx, int cy) {
    const int mx = (ax + bx) >> 1, my = (ay + by) >> 1;
    if (std::abs(ax - cx) + std::abs(ay - cy) > 1 &&
        errors[static_cast<size_t>(my) * static_cast<size_t>(size) + static_cast<size_t>(mx)] >
            max_error) {
      add(cx, cy, ax, ay, mx, my);
      add(bx, by, cx, cy, mx, my);
      return;
    }
    // Counter-clockwise on a map (y south): the cross product of (b - a)
    // and (c - a) in lattice axes is negative.
    const long cross =
        static_cast<long>(bx - ax) * (cy - ay) - static_cast<long>(by - ay) * (cx - ax);
    const uint32_t a = vertex(ax, ay);
    if (cross < 0) {
      const uint32_t b = vertex(bx, by);
      mesh.triangles.insert(mesh.triangles.end(), {a, b, vertex(cx, cy)});
    } else {
      const uint32_t c = vertex(cx, cy);
      mesh.triangles.insert(mesh.triangles.end(), {a, c, vertex(bx, by)});
    }
  }
};

}  // namespace

RtinMesh Rtin::mesh(std::span<const float> errors, float max_error) const {
  const size_t size = static_cast<size_t>(size_);
  assert(errors.size() == size * size);
  MeshBuilder b{errors, max_error, size_, std::vector<uint32_t>(size * size, 0), {}};
  const int max = size_ - 1;
  b.add(0, 0, max, max, max, 0);
  b.add(max, max, 0, 0, 0, max);
  return std::move(b.mesh);
}

}  // namespace relief::web
