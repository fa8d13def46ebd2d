// The quick bounds refinement decides most diamonds with
// (angle_bound_range.h) hold the exact angle bound of vertical_error_parts
// between them, for cubes of every size around points near and far, in front
// of and behind the eye, seen straight down, obliquely and at grazing angles:
// so a decision they settle is the exact criterion's.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <random>

#include "angle_bound_range.h"
#include "relief/lod/screen_error.h"

namespace relief::lod {
namespace {

constexpr double kDegree = 3.14159265358979323846 / 180;

struct Case {
  const char* name;
  Camera camera;
  double spread;  // degrees around the camera where the cubes are
};

const Case kCases[] = {
    {"straight down", {81, 30, 900e3, 0, -90, 0, 60, 1280, 720}, 8},
    {"straight down, low", {1.5, 42.5, 20e3, 0, -90, 0, 60, 1280, 720}, 0.3},
    {"oblique", look_at(1.5, 42.5, 1500, 60000, 20, -35, 60, 1280, 720), 1.2},
    {"grazing", {1.05, 42.05, 2300, 35, -4, 0, 60, 1280, 720}, 1},
    {"near the antimeridian, high latitude", {179.98, 71, 3000, 270, -20, 0, 90, 800, 800}, 0.5},
};

TEST(AngleBoundRange, HoldsTheExactAngleBoundBetweenItsBounds) {
  std::mt19937 rng(5);
  std::uniform_real_distribution<double> unit(0, 1);
  for (const Case& c : kCases) {
    SCOPED_TRACE(c.name);
    auto view = make_view(c.camera);
    ASSERT_TRUE(view);
    int in_front = 0, settled = 0;
    constexpr int kCubes = 20000;
    for (int i = 0; i < kCubes; ++i) {
      const double lon = c.camera.lon + c.spread * (2 * unit(rng) - 1);
      const double lat = std::clamp(c.camera.lat + c.spread * (2 * unit(rng) - 1), -89.0, 89.0);
      const double h = 4000 * unit(rng);
      // Areas of half-widths from a sample (~1e-5 degrees) to a tile.
      const double a = std::pow(10.0, -5 + 4.5 * unit(rng));
      const double half = std::pow(10.0, 5 * unit(rng));
      const double metres = std::pow(10.0, -2 + 4 * unit(rng));
      const Vec3 centre = ecef(lon, lat, h);
      const geo::GeoBox area{lon - a, lat - a, lon + a, lat + a};
      const Box box{centre - Vec3{half, half, half}, centre + Vec3{half, half, half}};
      const VerticalErrorParts e = vertical_error_parts(*view, box, area, metres);
      // The normal as refinement computes it differs from up_at() by rounding.
      const Vec3 up = up_at(lon, lat);
      const Vec3 normal = up * (1 + 1e-15 * (2 * unit(rng) - 1));
      const AngleBoundRange r =
          angle_bound_range(*view, centre, half, normal, 2 * a * kDegree, metres);
      if (!r.in_front) continue;
      ++in_front;
      ASSERT_FALSE(e.behind) << i;
      const double exact =
          view->pixels_per_radian * metres * (e.sin_bound + e.tangent * e.cos_bound) / e.z_min;
      ASSERT_LE(r.lo, exact) << i;
      ASSERT_GE(r.hi, exact) << i;
      ASSERT_LE(r.z_lo, e.z_min) << i;
      ASSERT_GE(r.z_hi, e.z_min) << i;
      ASSERT_LE(r.t_lo, e.tangent) << i;
      ASSERT_GE(r.t_hi, e.tangent) << i;
      ASSERT_LE(r.s_lo, e.sin_bound) << i;
      ASSERT_GE(r.s_hi, e.sin_bound) << i;
      ASSERT_LE(r.c_lo, e.cos_bound) << i;
      ASSERT_GE(r.c_hi, e.cos_bound) << i;
      // Close enough to settle a threshold 5 % away.
      settled += r.hi < exact * 1.05 && r.lo > exact / 1.05;
    }
    EXPECT_GT(in_front, kCubes / 4);
    EXPECT_GT(settled, in_front / 4);
  }
}

}  // namespace
}  // namespace relief::lod
