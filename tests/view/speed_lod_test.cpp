// Speed-dependent LOD: the threshold coarsens while the view moves, by its
// angular speed and its linear speed relative to the height above the
// ground, at most max_factor times; when the view stops it comes back and
// ends exactly at the still threshold.
#include <gtest/gtest.h>

#include "relief/view/speed_lod.h"

namespace relief::view {
namespace {

constexpr double kDt = 1.0 / 60;

TEST(SpeedLod, CoarsensWhileMovingAndReturnsExactlyToTheStillThreshold) {
  SpeedLod lod;  // doubles at 30 deg/s or one height above ground per second
  EXPECT_EQ(lod.threshold(1.5, kDt, 0, 0, 100), 1.5);
  EXPECT_DOUBLE_EQ(lod.threshold(1.5, kDt, 30, 0, 100), 3.0);
  EXPECT_DOUBLE_EQ(lod.threshold(1.5, kDt, 0, 100, 100), 3.0);
  EXPECT_DOUBLE_EQ(lod.threshold(1.5, kDt, 15, 50, 100), 3.0);
  EXPECT_DOUBLE_EQ(lod.threshold(1.5, kDt, 0, 1000, 100), 6.0);  // capped at 4 times
  EXPECT_DOUBLE_EQ(lod.factor(), 4);
  // Stopped: smooth (every frame finer than the one before), then exactly the still.
  double previous = 6.0;
  int frames = 0;
  for (; frames < 600; ++frames) {
    const double t = lod.threshold(1.5, kDt, 0, 0, 100);
    ASSERT_LT(t, previous);
    if (t == 1.5) break;
    ASSERT_LE(previous / t, 1.06);  // no jump before the end
    previous = t;
  }
  EXPECT_LT(frames, 120);  // 0.3 s time constant: back in under 2 s
  EXPECT_EQ(lod.factor(), 1);
  EXPECT_EQ(lod.threshold(1.5, kDt, 0, 0, 100), 1.5);
}

TEST(SpeedLod, SlowMotionRelaxesLittleAndDisabledNever) {
  SpeedLod lod;
  EXPECT_DOUBLE_EQ(lod.threshold(1, kDt, 0, 1, 10000), 1);  // 1 m/s at 10 km: still
  EXPECT_NEAR(lod.threshold(1, kDt, 3, 0, 100), 1.1, 1e-12);
  SpeedLodOptions off;
  off.enabled = false;
  SpeedLod none(off);
  EXPECT_EQ(none.threshold(2, kDt, 90, 1000, 10), 2);
}

}  // namespace
}  // namespace relief::view
