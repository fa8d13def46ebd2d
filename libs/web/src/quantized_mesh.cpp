#include "relief/web/quantized_mesh.h"

#include <algorithm>
#include <bit>
#include <cassert>
#include <cmath>
#include <cstring>
#include <limits>
#include <numbers>

namespace relief::web {
namespace {

class Writer {
 public:
  template <class T>
  void put(T value) {
    static_assert(std::endian::native == std::endian::little);
    const auto* p = reinterpret_cast<const std::byte*>(&value);
    bytes_.insert(bytes_.end(), p, p + sizeof(T));
  }
  void put_bytes(const void* data, size_t n) {
    const auto* p = static_cast<const std::byte*>(data);
    bytes_.insert(bytes_.end(), p, p + n);
  }
  size_t size() const { return bytes_.size(); }
  std::vector<std::byte> take() { return std::move(bytes_); }

 private:
  std::vector<std::byte> bytes_;
};

// Each array is delta coded from 0, then zig-zag coded into 16 bits.
void put_zigzag_deltas(Writer& w, const std::vector<uint16_t>& values) {
  int previous = 0;
  for (const uint16_t value : values) {
    const int delta = value - previous;
    previous = value;
    w.put(static_cast<uint16_t>((delta << 1) ^ (delta >> 31)));
  }
}

template <class Index>
void put_indices(Writer& w, const QuantizedMeshInput& in,
                 const std::vector<std::vector<uint32_t>>& edges) {
  // High-water-mark coding: each index as its distance below the next new
  // vertex, 0 for the next new vertex itself.
  w.put(static_cast<uint32_t>(in.triangles.size() / 3));
  uint32_t highest = 0;
  for (const uint32_t index : in.triangles) {
    assert(index <= highest && "vertices must be numbered by first use");
    w.put(static_cast<Index>(highest - index));
    if (index == highest) ++highest;
  }
  for (const auto& edge : edges) {
    w.put(static_cast<uint32_t>(edge.size()));
    for (const uint32_t index : edge) w.put(static_cast<Index>(index));
  }
}

geo::Ecef scaled(const geo::Ecef& p) {
  return {p.x / geo::wgs84::kSemiMajorAxis, p.y / geo::wgs84::kSemiMajorAxis,
          p.z / geo::wgs84::kSemiMinorAxis};
}
double dot(const geo::Ecef& a, const geo::Ecef& b) {
  return a.x * b.x + a.y * b.y + a.z * b.z;
}
double length(const geo::Ecef& a) {
  return std::sqrt(dot(a, a));
}
geo::Ecef times(const geo::Ecef& a, double s) {
  return {a.x * s, a.y * s, a.z * s};
}

double lerp(double a, double b, double t) {
  return (1 - t) * a + t * b;
}

}  // namespace

double cesium_level_error(int level) {
  return geo::wgs84::kSemiMajorAxis * 2 * std::numbers::pi * 0.25 / (65 * 2) /
         std::ldexp(1.0, level);
}

void oct_encode(const geo::Ecef& n, uint8_t& x, uint8_t& y) {
  const double s = std::abs(n.x) + std::abs(n.y) + std::abs(n.z);
  double ox = n.x / s, oy = n.y / s;
  if (n.z < 0) {
    const auto sign = [](double v) { return v < 0 ? -1.0 : 1.0; };
    const double t = ox;
    ox = (1 - std::abs(oy)) * sign(t);
    oy = (1 - std::abs(t)) * sign(oy);
  }
  // Math.round rounds halves up; std::round away from zero: equal here, the
  // argument is never negative.
  const auto to_byte = [](double v) {
    return static_cast<uint8_t>(std::round((std::clamp(v, -1.0, 1.0) * 0.5 + 0.5) * 255));
  };
  x = to_byte(ox);
  y = to_byte(oy);
}

std::optional<geo::Ecef> horizon_occlusion_point(const std::vector<geo::Ecef>& points,
                                                 const geo::Ecef& direction) {
  geo::Ecef d = scaled(direction);
  d = times(d, 1 / length(d));
  double magnitude = 0;
  for (const geo::Ecef& p : points) {
    const geo::Ecef q = scaled(p);
    double m2 = dot(q, q);
    double m = std::sqrt(m2);
    const geo::Ecef w = times(q, 1 / m);
    // Points below the ellipsoid count as on it.
    m2 = std::max(1.0, m2);
    m = std::max(1.0, m);
    const double cos_a = dot(w, d);
    // A point 90 degrees or more from the direction (the half-globe tiles
    // of level 0) needs a point at infinity, or none.
    if (cos_a <= 1e-9) return std::nullopt;
    const geo::Ecef c{w.y * d.z - w.z * d.y, w.z * d.x - w.x * d.z, w.x * d.y - w.y * d.x};
    const double sin_a = length(c);
    const double cos_b = 1 / m, sin_b = std::sqrt(m2 - 1) * cos_b;
    const double candidate = 1 / (cos_a * cos_b - sin_a * sin_b);
    if (!(candidate > 0) || !std::isfinite(candidate)) return std::nullopt;
    magnitude = std::max(magnitude, candidate);
  }
  if (!(magnitude > 0) || !std::isfinite(magnitude)) return std::nullopt;
  return times(d, magnitude);
}

std::vector<std::byte> encode_quantized_mesh(const QuantizedMeshInput& in) {
  const size_t n = in.u.size();
  assert(in.v.size() == n && in.height.size() == n);
  assert(in.normals.empty() || in.normals.size() == n);
  assert(n > 0 && in.triangles.size() % 3 == 0);

  float lo = std::numeric_limits<float>::infinity(), hi = -lo;
  for (const float h : in.height) lo = std::min(lo, h), hi = std::max(hi, h);
  std::vector<uint16_t> hq(n);
  std::vector<geo::Ecef> positions(n);  // as a client decodes them
  geo::Ecef box_lo{1e300, 1e300, 1e300}, box_hi{-1e300, -1e300, -1e300};
  for (size_t i = 0; i < n; ++i) {
    const double t = hi > lo ? (static_cast<double>(in.height[i]) - lo) / (hi - lo) : 0.0;
    hq[i] = static_cast<uint16_t>(std::lround(t * kQuantizedMax));
    const geo::Geodetic g{lerp(in.rect.west, in.rect.east, in.u[i] / double(kQuantizedMax)),
                          lerp(in.rect.south, in.rect.north, in.v[i] / double(kQuantizedMax)),
                          lerp(lo, hi, hq[i] / double(kQuantizedMax))};
    positions[i] = geo::to_ecef(g);
    const geo::Ecef& p = positions[i];
    box_lo = {std::min(box_lo.x, p.x), std::min(box_lo.y, p.y), std::min(box_lo.z, p.z)};
    box_hi = {std::max(box_hi.x, p.x), std::max(box_hi.y, p.y), std::max(box_hi.z, p.z)};
  }
  const geo::Ecef sphere{(box_lo.x + box_hi.x) / 2, (box_lo.y + box_hi.y) / 2,
                         (box_lo.z + box_hi.z) / 2};
  double radius = 0;
  for (const geo::Ecef& p : positions) {
    radius = std::max(radius, length({p.x - sphere.x, p.y - sphere.y, p.z - sphere.z}));
  }
  const double mid_lon = (in.rect.west + in.rect.east) / 2;
  const double mid_lat = (in.rect.south + in.rect.north) / 2;
  const geo::Ecef centre = geo::to_ecef({mid_lon, mid_lat, (double(lo) + hi) / 2});
  // Seen along the rectangle's centre at the surface, as CesiumJS does.
  const auto hop = horizon_occlusion_point(positions, geo::to_ecef({mid_lon, mid_lat, 0}));
  const double nan = std::numeric_limits<double>::quiet_NaN();

  Writer w;
  w.put(centre.x), w.put(centre.y), w.put(centre.z);
  w.put(lo), w.put(hi);
  w.put(sphere.x), w.put(sphere.y), w.put(sphere.z), w.put(radius);
  // No conservative point exists for a tile reaching 90 degrees from its
  // centre (level 0): NaN makes every `>` test of CesiumJS's culling false,
  // so the tile is never culled by the horizon.
  w.put(hop ? hop->x : nan), w.put(hop ? hop->y : nan), w.put(hop ? hop->z : nan);
  w.put(static_cast<uint32_t>(n));
  put_zigzag_deltas(w, in.u);
  put_zigzag_deltas(w, in.v);
  put_zigzag_deltas(w, hq);

  std::vector<std::vector<uint32_t>> edges(4);  // west, south, east, north
  for (size_t i = 0; i < n; ++i) {
    const auto index = static_cast<uint32_t>(i);
    if (in.u[i] == 0) edges[0].push_back(index);
    if (in.v[i] == 0) edges[1].push_back(index);
    if (in.u[i] == kQuantizedMax) edges[2].push_back(index);
    if (in.v[i] == kQuantizedMax) edges[3].push_back(index);
  }
  if (n > 65536) {
    // 32-bit indices start on a multiple of 4 from the buffer's start.
    if (w.size() % 4 == 2) w.put(uint16_t{0});
    put_indices<uint32_t>(w, in, edges);
  } else {
    put_indices<uint16_t>(w, in, edges);
  }

  if (!in.normals.empty()) {
    w.put(uint8_t{1});
    w.put(static_cast<uint32_t>(2 * n));
    for (const geo::Ecef& normal : in.normals) {
      uint8_t xy[2];
      oct_encode(normal, xy[0], xy[1]);
      w.put_bytes(xy, 2);
    }
  }
  if (in.metadata_json) {
    const auto json_length = static_cast<uint32_t>(in.metadata_json->size());
    w.put(uint8_t{4});
    w.put(static_cast<uint32_t>(4 + json_length));
    w.put(json_length);
    w.put_bytes(in.metadata_json->data(), json_length);
  }
  return w.take();
}

}  // namespace relief::web
