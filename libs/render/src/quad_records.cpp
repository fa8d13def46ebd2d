#include "quad_records.h"

#include <algorithm>
#include <cmath>

#include "relief/geo/ellipsoid.h"

namespace relief::render {

namespace {

constexpr double kDeg = 3.14159265358979323846 / 180;

// Corner (x, y) of the lattice of level `level`, in degrees: exact (dyadic
// multiples of 360 and 180), so a point reached from any level is the same
// double; the antimeridian is -180 from both sides.
void corner_degrees(int level, uint64_t x, uint64_t y, double& lon, double& lat) {
  const uint64_t n = uint64_t{1} << level;
  lon = -180.0 + static_cast<double>(x % n) * std::ldexp(360.0, -level);
  lat = 90.0 - static_cast<double>(y) * std::ldexp(180.0, -level);
}

}  // namespace

const QuadRecords::Corners& QuadRecords::corners(const geo::TileKey& key) {
  if (auto it = cache_.find(key); it != cache_.end()) return it->second;
  if (cache_.size() >= kMaxCached) cache_.clear();
  Corners c;
  for (int i = 0; i < 8; ++i) {
    const bool parent = i >= 4 && key.level > 0;
    const int level = parent ? key.level - 1 : key.level;
    const uint64_t x = (parent ? key.x >> 1 : key.x) + (i & 1),
                   y = (parent ? key.y >> 1 : key.y) + ((i >> 1) & 1);
    double lon, lat;
    corner_degrees(level, x, y, lon, lat);
    c.ecef[i] = lod::ecef(lon, lat, 0);
    const double p = lat * kDeg, l = lon * kDeg, s = std::sin(p);
    const double t[4] = {std::cos(p), s, std::cos(l), std::sin(l)};
    for (int k = 0; k < 4; ++k) c.trig[i][k] = static_cast<float>(t[k]);
    c.radius[i] = static_cast<float>(geo::wgs84::prime_vertical_radius(s));
  }
  return cache_.emplace(key, c).first->second;
}

QuadRecord QuadRecords::make(const lod::SelectedQuad& q, const lod::Vec3& eye) {
  const Corners& c = corners(q.key);
  QuadRecord r{};
  for (int i = 0; i < 8; ++i) {
    const lod::Vec3 d = c.ecef[i] - eye;
    r.anchor[i][0] = static_cast<float>(d.x);
    r.anchor[i][1] = static_cast<float>(d.y);
    r.anchor[i][2] = static_cast<float>(d.z);
    r.anchor[i][3] = c.radius[i];
    for (int k = 0; k < 4; ++k) r.trig[i][k] = c.trig[i][k];
  }
  const geo::GeoBox b = q.key.bounds();
  r.size[0] = static_cast<float>(b.width());
  r.size[1] = static_cast<float>(b.height());
  r.size[2] = static_cast<float>(b.north);
  r.size[3] = static_cast<float>(b.south);
  r.slots[3] = static_cast<uint32_t>(q.coarse_sides) << 4 |
               static_cast<uint32_t>(q.coarse_corners) << 8 | (q.key.x & 1u) << 12 |
               (q.key.y & 1u) << 13 | static_cast<uint32_t>(q.parent_data_sides) << 14 |
               static_cast<uint32_t>(q.parent_data_corners) << 18 | kNormalFloat;
  return r;
}

float nearness(const QuadRecord& r) {
  float centre[3] = {};
  for (int c = 0; c < 4; ++c) {
    for (int i = 0; i < 3; ++i) centre[i] += 0.25f * r.anchor[c][i];
  }
  float reach = 0;
  for (int c = 0; c < 4; ++c) {
    reach = std::max(reach, std::hypot(r.anchor[c][0] - centre[0], r.anchor[c][1] - centre[1],
                                       r.anchor[c][2] - centre[2]));
  }
  return std::hypot(centre[0], centre[1], centre[2]) - reach;
}

}  // namespace relief::render
