#include "relief/lod/refined_evaluator.h"

#include <algorithm>

namespace relief::lod {

namespace {

uint64_t triangle_key(uint32_t a, uint32_t b, uint32_t c) {
  uint32_t v[3] = {a, b, c};
  std::sort(v, v + 3);
  return uint64_t{v[0]} << 42 | uint64_t{v[1]} << 21 | v[2];
}

// Barycentric weights of (x, y) in triangle (p0, p1, p2), with a tolerance.
bool inside(GridPos p0, GridPos p1, GridPos p2, double x, double y, double* w) {
  const double d = double(p1.x - p0.x) * (p2.y - p0.y) - double(p2.x - p0.x) * (p1.y - p0.y);
  const double s = ((x - p0.x) * (p2.y - p0.y) - (p2.x - p0.x) * (y - p0.y)) / d;
  const double r = ((p1.x - p0.x) * (y - p0.y) - (x - p0.x) * (p1.y - p0.y)) / d;
  if (s < -1e-9 || r < -1e-9 || s + r > 1 + 1e-9) return false;
  w[0] = 1 - s - r, w[1] = s, w[2] = r;
  return true;
}

}  // namespace

RefinedEvaluator::RefinedEvaluator(TerrainModel& terrain, const Selection& s, const RefinedMesh& m)
    : mesh_(m), eval_(terrain, s), n_(1 << m.grid_k) {
  triangles_.resize(s.quads.size());
  for (size_t q = 0; q < s.quads.size() && q < m.quads.size(); ++q) {
    index_[s.quads[q].key] = q;
    const RefinedQuad& rq = m.quads[q];
    for (uint32_t i = rq.first_index; i + 2 < rq.first_index + rq.index_count; i += 3) {
      triangles_[q].insert(triangle_key(m.indices[i], m.indices[i + 1], m.indices[i + 2]));
    }
  }
}

GridPos RefinedEvaluator::pos(uint32_t id) const {
  const GridVertexPosition p = grid_vertex_position(mesh_.grid_k, id);
  return {static_cast<int>(p.i), static_cast<int>(p.j)};
}

uint32_t RefinedEvaluator::id(GridPos p) const {
  return grid_vertex_id(mesh_.grid_k, static_cast<uint32_t>(p.x), static_cast<uint32_t>(p.y));
}

std::pair<double, double> RefinedEvaluator::lonlat(const SelectedQuad& q, GridPos p) const {
  const geo::GeoBox b = q.key.bounds();
  double lon = b.west + p.x / (2.0 * n_) * b.width();
  if (lon >= 180) lon -= 360;
  return {lon, b.north - p.y / double(n_) * b.height()};
}

Result<double> RefinedEvaluator::height(const SelectedQuad& q, GridPos p) {
  MeshVertex v;
  v.u = static_cast<float>(p.x / (2.0 * n_));
  v.v = static_cast<float>(p.y / double(n_));
  if (p.x == 0) v.sides |= kWest;
  if (p.x == 2 * n_) v.sides |= kEast;
  if (p.y == 0) v.sides |= kNorth;
  if (p.y == n_) v.sides |= kSouth;
  const uint8_t s = v.sides;
  if ((s & kNorth) && (s & kWest)) v.corner = kNorthWest;
  if ((s & kNorth) && (s & kEast)) v.corner = kNorthEast;
  if ((s & kSouth) && (s & kWest)) v.corner = kSouthWest;
  if ((s & kSouth) && (s & kEast)) v.corner = kSouthEast;
  return eval_.vertex_height(q, v);
}

Result<std::optional<Vec3>> RefinedEvaluator::point(const SelectedQuad& q, double lon, double lat) {
  const auto it = index_.find(q.key);
  if (it == index_.end()) return std::optional<Vec3>();
  const size_t qi = it->second;
  const geo::GeoBox b = q.key.bounds();
  const double cell = b.height() / n_;
  const double gx = (lon - b.west) / cell, gy = (b.north - lat) / cell;
  const int h = gx < n_ ? 0 : 1;
  const GridPos c{h * n_ + n_ / 2, n_ / 2}, nw{h * n_, 0}, ne{h * n_ + n_, 0}, se{h * n_ + n_, n_},
      sw{h * n_, n_};
  const GridPos roots[4][2] = {{nw, ne}, {ne, se}, {se, sw}, {sw, nw}};
  GridPos t[3];
  bool found = false;
  double w[3];
  for (const auto& r : roots) {
    if (inside(c, r[0], r[1], gx, gy, w)) {
      t[0] = c, t[1] = r[0], t[2] = r[1];
      found = true;
      break;
    }
  }
  if (!found) return std::optional<Vec3>();
  for (int depth = 0; depth < 40; ++depth) {
    if (triangles_[qi].contains(triangle_key(id(t[0]), id(t[1]), id(t[2])))) {
      Vec3 out;
      for (int k = 0; k < 3; ++k) {
        const auto [vlon, vlat] = lonlat(q, t[k]);
        out = out + ecef(vlon, vlat, RELIEF_TRY(height(q, t[k]))) * w[k];
      }
      return std::optional<Vec3>(out);
    }
    // Descend: the triangle's children share the midpoint of its hypotenuse.
    const GridPos m{(t[1].x + t[2].x) / 2, (t[1].y + t[2].y) / 2};
    const GridPos r = t[0], a = t[1], bb = t[2];
    if (inside(m, a, r, gx, gy, w)) {
      t[0] = m, t[1] = a, t[2] = r;
    } else if (inside(m, r, bb, gx, gy, w)) {
      t[0] = m, t[1] = r, t[2] = bb;
    } else {
      return std::optional<Vec3>();
    }
  }
  return std::optional<Vec3>();
}

}  // namespace relief::lod
