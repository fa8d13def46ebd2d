#pragma once
// Small double-precision vector algebra for cameras and bounds.
#include <cmath>

namespace relief::lod {

struct Vec3 {
  double x = 0, y = 0, z = 0;
  Vec3 operator+(const Vec3& o) const { return {x + o.x, y + o.y, z + o.z}; }
  Vec3 operator-(const Vec3& o) const { return {x - o.x, y - o.y, z - o.z}; }
  Vec3 operator*(double s) const { return {x * s, y * s, z * s}; }
  Vec3 operator-() const { return {-x, -y, -z}; }
};

inline double dot(const Vec3& a, const Vec3& b) {
  return a.x * b.x + a.y * b.y + a.z * b.z;
}
inline Vec3 cross(const Vec3& a, const Vec3& b) {
  return {a.y * b.z - a.z * b.y, a.z * b.x - a.x * b.z, a.x * b.y - a.y * b.x};
}
inline double length(const Vec3& a) {
  return std::sqrt(dot(a, a));
}
inline Vec3 normalize(const Vec3& a) {
  return a * (1.0 / length(a));
}

// An axis-aligned box in ECEF metres.
struct Box {
  Vec3 lo, hi;
};

// Distance from a point to the nearest point of the box (0 inside).
double distance_to(const Box& box, const Vec3& point);

// Geodetic surface normal (the "up" of the local east-north-up frame).
Vec3 up_at(double lon_deg, double lat_deg);
Vec3 east_at(double lon_deg);
Vec3 north_at(double lon_deg, double lat_deg);
Vec3 ecef(double lon_deg, double lat_deg, double height_m);

}  // namespace relief::lod
