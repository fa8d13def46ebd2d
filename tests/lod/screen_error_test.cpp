// vertical_error_pixels is an upper bound: random vertical segments inside
// quads, seen from straight down, oblique and grazing views, never move on
// screen by more than it says; it falls towards 0 seen from above and is the
// distance bound at grazing angles; and the plain distance bound δK/d, used
// before, is exceeded towards the screen's edges.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <random>

#include "relief/lod/screen_error.h"

namespace relief::lod {
namespace {

// An ECEF box around the quad's surface between heights lo and hi: dense
// points at both heights, padded by the bulge of the ellipsoid between them.
Box box_of(const geo::GeoBox& b, double lo, double hi) {
  Box box{{INFINITY, INFINITY, INFINITY}, {-INFINITY, -INFINITY, -INFINITY}};
  constexpr int kN = 16;
  for (int j = 0; j <= kN; ++j) {
    for (int i = 0; i <= kN; ++i) {
      for (double h : {lo, hi}) {
        const Vec3 p = ecef(b.west + b.width() * i / kN, b.south + b.height() * j / kN, h);
        box.lo = {std::min(box.lo.x, p.x), std::min(box.lo.y, p.y), std::min(box.lo.z, p.z)};
        box.hi = {std::max(box.hi.x, p.x), std::max(box.hi.y, p.y), std::max(box.hi.z, p.z)};
      }
    }
  }
  const double step = std::max(b.width(), b.height()) / kN * 3.14159265358979323846 / 180;
  const double pad = 6378137.0 * (1 - std::cos(step / 2)) + 1;
  box.lo = box.lo - Vec3{pad, pad, pad};
  box.hi = box.hi + Vec3{pad, pad, pad};
  return box;
}

struct Case {
  const char* name;
  Camera camera;
  double spread;  // degrees around the camera where the segments are
};

const Case kCases[] = {
    {"straight down", {81, 30, 900e3, 0, -90, 0, 60, 1280, 720}, 8},
    {"straight down, low", {1.5, 42.5, 20e3, 0, -90, 0, 60, 1280, 720}, 0.3},
    {"oblique", look_at(1.5, 42.5, 1500, 60000, 20, -35, 60, 1280, 720), 1.2},
    {"grazing", {1.05, 42.05, 2300, 35, -4, 0, 60, 1280, 720}, 1},
    {"near the antimeridian, high latitude", {179.98, 71, 3000, 270, -20, 0, 90, 800, 800}, 0.5},
};

TEST(ScreenError, RandomVerticalSegmentsStayWithinTheBound) {
  std::mt19937 rng(11);
  std::uniform_real_distribution<double> unit(0, 1);
  for (const Case& c : kCases) {
    SCOPED_TRACE(c.name);
    auto view = make_view(c.camera);
    ASSERT_TRUE(view);
    int compared = 0;
    double tightest = 0;  // largest measured / bound
    for (int trial = 0; trial < 4000; ++trial) {
      // A point near the camera, and a quad holding it.
      const int level = 6 + static_cast<int>(rng() % 11);
      const double n = std::ldexp(1.0, level);
      const double plon = std::fmod(c.camera.lon + (unit(rng) - 0.5) * c.spread + 540, 360) - 180;
      const double plat = c.camera.lat + (unit(rng) - 0.5) * c.spread;
      const geo::TileKey key{level, static_cast<uint32_t>((plon + 180) / 360 * n),
                             static_cast<uint32_t>((90 - plat) / 180 * n)};
      const geo::GeoBox area = key.bounds();
      const double lo = -100 + unit(rng) * 3000, hi = lo + unit(rng) * 5000;
      const Box box = box_of(area, lo, hi);
      const double h1 = lo + unit(rng) * (hi - lo), h2 = lo + unit(rng) * (hi - lo);
      double ax, ay, bx, by;
      if (!view->project(ecef(plon, plat, h1), ax, ay) ||
          !view->project(ecef(plon, plat, h2), bx, by))
        continue;
      auto on_screen = [&](double x, double y) {
        return x >= 0 && y >= 0 && x <= view->width && y <= view->height;
      };
      if (!on_screen(ax, ay) || !on_screen(bx, by)) continue;
      const double moved = std::hypot(ax - bx, ay - by);
      const double bound = vertical_error_pixels(*view, box, area, std::abs(h1 - h2));
      ASSERT_LE(moved, bound * (1 + 1e-9) + 1e-9)
          << "level " << level << " at " << plon << "," << plat << " heights " << h1 << "," << h2;
      if (bound > 0) tightest = std::max(tightest, moved / bound);
      ++compared;
    }
    EXPECT_GT(compared, 200);
    EXPECT_GT(tightest, 0.2);  // a bound, not a wild overestimate
  }
}

TEST(ScreenError, FallsTowardsZeroSeenFromAboveAndIsTheDistanceBoundAtGrazingAngles) {
  // A quad at the centre of a straight-down view.
  auto down = make_view({81, 30, 900e3, 0, -90, 0, 60, 1280, 720});
  ASSERT_TRUE(down);
  const geo::TileKey centre{12, static_cast<uint32_t>((81.0 + 180) / 360 * 4096),
                            static_cast<uint32_t>((90 - 30.0) / 180 * 4096)};
  const Box box = box_of(centre.bounds(), 0, 100);
  const double d = distance_to(box, down->eye);
  const double plain = 100 * down->pixels_per_radian / d;
  EXPECT_LT(vertical_error_pixels(*down, box, centre.bounds(), 100), 0.05 * plain);
  // Grazing: the vertical is nearly across the view direction.
  auto low = make_view({1.05, 42.05, 2300, 35, -4, 0, 60, 1280, 720});
  ASSERT_TRUE(low);
  const geo::TileKey ahead{14, static_cast<uint32_t>((1.15 + 180) / 360 * 16384),
                           static_cast<uint32_t>((90 - 42.12) / 180 * 16384)};
  const Box far = box_of(ahead.bounds(), 0, 100);
  const double plain_far = 100 * low->pixels_per_radian / distance_to(far, low->eye);
  const double bound = vertical_error_pixels(*low, far, ahead.bounds(), 100);
  EXPECT_GT(bound, 0.9 * plain_far);
  EXPECT_LT(bound, 2.5 * plain_far);
}

// The sine and cosine bounds come from angle-sum identities (one sincos per
// quad): they equal those of the angle range itself, [centre - spread, centre
// + spread] clamped to [0, pi], for quads of every size all around views of
// every kind, including a range holding the right angle and ranges clamped at
// either end.
TEST(ScreenError, AngleBoundsEqualThoseOfTheClampedAngleRange) {
  constexpr double kDeg = 3.14159265358979323846 / 180, kPi = 3.14159265358979323846;
  std::mt19937 rng(11);
  std::uniform_real_distribution<double> unit(0, 1);
  int checked = 0, holding_right_angle = 0, clamped = 0;
  for (const Case& c : kCases) {
    auto view = make_view(c.camera);
    ASSERT_TRUE(view) << c.name;
    for (int i = 0; i < 400; ++i) {
      const int level = 2 + static_cast<int>(unit(rng) * 14);
      const double size = 180.0 / (1 << level);
      const double lon = c.camera.lon + (unit(rng) - 0.5) * 8;
      const double lat = std::min(c.camera.lat + (unit(rng) - 0.5) * 8, 90 - size);
      const geo::GeoBox area{lon, lat, lon + size, lat + size};
      // Far below the eye, so no corner is behind it and the bounds are computed.
      const Box box = box_of(area, -20000, -10000);
      const VerticalErrorParts e = vertical_error_parts(*view, box, area, 10);
      if (e.behind) continue;
      const double centre = std::acos(
          std::clamp(dot(up_at(lon + size / 2, lat + size / 2), view->forward), -1.0, 1.0));
      const double spread = size * kDeg;
      const double lo = std::max(0.0, centre - spread), hi = std::min(kPi, centre + spread);
      const bool right = lo <= kPi / 2 && hi >= kPi / 2;
      const double s = right ? 1.0 : std::max(std::sin(lo), std::sin(hi));
      const double co = std::max(std::abs(std::cos(lo)), std::abs(std::cos(hi)));
      EXPECT_NEAR(e.sin_bound, s, 1e-9) << c.name << " " << lon << " " << lat << " " << level;
      EXPECT_NEAR(e.cos_bound, co, 1e-9) << c.name << " " << lon << " " << lat << " " << level;
      ++checked;
      holding_right_angle += right;
      clamped += lo == 0 || hi == kPi;
    }
  }
  EXPECT_GT(checked, 1000);
  EXPECT_GT(holding_right_angle, 10);
  EXPECT_GT(clamped, 10);
}

TEST(ScreenError, TheDistanceBoundAloneIsExceededAtTheScreensEdge) {
  // A vertical segment at the left edge of a 16:9 view, level with the eye:
  // it moves f·δ/(d·cos φ) pixels, more than δK/d.
  auto view = make_view({0, 0, 1000, 0, 0, 0, 60, 1280, 720});
  ASSERT_TRUE(view);
  const Vec3 side =
      view->eye + view->forward * 10000 - view->right * (10000 * view->tan_half_x * 0.98);
  const Vec3 up = side * (1 / length(side));
  const double delta = 10;
  double ax, ay, bx, by;
  ASSERT_TRUE(view->project(side, ax, ay));
  ASSERT_TRUE(view->project(side + up * delta, bx, by));
  const double moved = std::hypot(ax - bx, ay - by);
  const double d = length(side - view->eye);
  EXPECT_GT(moved, 1.3 * delta * view->pixels_per_radian / d);
}

}  // namespace
}  // namespace relief::lod
