// Planet-scale precision: with positions made relative to the eye in double
// and only then converted to float (as the renderer does), points near a
// camera 1 m above the ground project to within a hundredth of a pixel of
// their exact projection anywhere on Earth, and a 1 mm camera move shifts
// them by the expected amount: no jitter.
#include <gtest/gtest.h>

#include "relief/lod/camera.h"

namespace relief::lod {
namespace {

// The renderer's path: float(p - eye), then float arithmetic.
bool project_float(const View& v, const Vec3& p, double& sx, double& sy) {
  const Vec3 d = p - v.eye;
  const float rel[3] = {static_cast<float>(d.x), static_cast<float>(d.y), static_cast<float>(d.z)};
  auto fdot = [&](const Vec3& axis) {
    return rel[0] * static_cast<float>(axis.x) + rel[1] * static_cast<float>(axis.y) +
           rel[2] * static_cast<float>(axis.z);
  };
  const float z = fdot(v.forward);
  if (z <= 0) return false;
  sx = (fdot(v.right) / (z * static_cast<float>(v.tan_half_x)) + 1) * 0.5 * v.width;
  sy = (1 - fdot(v.up) / (z * static_cast<float>(v.tan_half_y))) * 0.5 * v.height;
  return true;
}

TEST(Precision, OneMetreAboveTheGroundAnywhere) {
  const double places[][2] = {{0, 0},           {1.5, 42.5}, {179.9999, 10},
                              {-179.9999, -33}, {25, 85},    {-60, -80}};
  for (const auto& place : places) {
    SCOPED_TRACE(std::to_string(place[0]) + "," + std::to_string(place[1]));
    Camera c{place[0], place[1], 1.0, 30, -20, 0, 60, 1920, 1080};
    auto v0 = make_view(c);
    ASSERT_TRUE(v0);
    Camera moved = c;
    moved.height += 0.001;  // 1 mm up
    auto v1 = make_view(moved);
    ASSERT_TRUE(v1);
    double worst = 0, worst_shift = 0;
    for (double dist : {2.0, 5.0, 20.0, 100.0, 1000.0}) {
      for (double side : {-0.3, 0.0, 0.3}) {
        const Vec3 p =
            v0->eye + v0->forward * dist + v0->right * (side * dist) - v0->up * (0.2 * dist);
        double ex, ey, fx, fy, ex1, ey1, fx1, fy1;
        ASSERT_TRUE(v0->project(p, ex, ey) && project_float(*v0, p, fx, fy));
        ASSERT_TRUE(v1->project(p, ex1, ey1) && project_float(*v1, p, fx1, fy1));
        worst = std::max({worst, std::abs(ex - fx), std::abs(ey - fy)});
        // The float image moves as the exact one does.
        worst_shift = std::max(worst_shift, std::abs((fy1 - fy) - (ey1 - ey)));
        // 1 mm at >= 2 m is at most ~0.5 px here: sub-pixel.
        EXPECT_LT(std::abs(ey1 - ey), 0.6);
      }
    }
    EXPECT_LT(worst, 0.01);
    EXPECT_LT(worst_shift, 0.01);
  }
}

TEST(Precision, CamerasInsideTheEllipsoidOrWithBadViewportsAreErrors) {
  EXPECT_FALSE(make_view(Camera{0, 0, -5000, 0, 0, 0, 60, 100, 100}));
  EXPECT_FALSE(make_view(Camera{0, 0, 100, 0, 0, 0, 60, 0, 100}));
  EXPECT_FALSE(make_view(Camera{0, 0, 100, 0, 0, 0, 60, 100000, 100}));
  EXPECT_FALSE(make_view(Camera{0, 0, 100, 0, 0, 0, 180, 100, 100}));
  EXPECT_FALSE(make_view(Camera{0, 95, 100, 0, 0, 0, 60, 100, 100}));
  EXPECT_TRUE(make_view(Camera{0, 0, 100, 0, 0, 0, 60, 100, 100}));
}

}  // namespace
}  // namespace relief::lod
