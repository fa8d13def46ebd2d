// Speed-dependent LOD: the threshold coarsens while the view moves, by its
// angular speed and its linear speed relative to the height above the
// ground, at most max_factor times; when the view stops it comes back and
// ends exactly at the still threshold.
#include <gtest/gtest.h>

#include "controls_input.h"
#include "loaded_scene.h"
#include "relief/view/ground.h"
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

// In a scene: an orbit turning at 60 degrees per second draws a coarser
// selection; once it stops the threshold comes back to the still one and the
// frames converge to the complete still of the camera, pixel for pixel.
class SpeedLodSceneTest : public view::testing::LoadedSceneTest {};

TEST_F(SpeedLodSceneTest, TurningCoarsensAndStoppingConvergesToTheCompleteStill) {
  const lod::Camera start = lod::look_at(1.5, 42.6, 1500, 8000, 20, -60, 60, 160, 120);
  load(start);
  const Ground ground = resident_ground(*scene_);
  auto orbit = make_controller(ControlMode::orbit, start);
  SpeedLod speed;
  auto frame = [&](double dt) {
    const lod::Camera& c = orbit->update(dt, ground);
    const double above = c.height - *ground(c.lon, c.lat);
    const double pixels =
        speed.threshold(1.0, dt, orbit->angular_speed(), orbit->linear_speed(), above);
    scene_->set_pixel_error(pixels);
    auto f = scene_->draw(c, *target_);
    EXPECT_TRUE(f) << f.error().message;
    return std::make_pair(pixels, f ? f->draw.triangles : 0);
  };
  orbit->push(view::testing::key_down(Key::q));
  for (int i = 0; i < 5; ++i) {
    const auto [pixels, triangles] = frame(kDt);
    if (i > 0) {
      EXPECT_GT(pixels, 3);  // 1 + 60 / 30 + the eye's speed round the point
    }
  }
  orbit->push(view::testing::key_up(Key::q));
  // Stopped: still relaxed, then back (in steps of 0.1 s: 0.3 s time constant).
  const auto [first_pixels, first_triangles] = frame(0.1);
  EXPECT_GT(first_pixels, 2.5);
  uint64_t triangles = 0;
  bool complete = false;
  for (int i = 0; i < 60 && !complete; ++i) {
    wait_idle();
    const auto [pixels, t] = frame(0.1);
    triangles = t;
    complete = pixels == 1.0 && scene_->last_selection().stats.waiting == 0;
  }
  ASSERT_TRUE(complete);
  EXPECT_GT(triangles, first_triangles);
  auto last = scene_->draw(orbit->camera(), *target_);
  ASSERT_TRUE(last);
  EXPECT_TRUE(last->complete);
  const std::vector<uint8_t> live = *target_->read_rgba();

  SceneOptions o;
  o.interactive = false;
  o.mesh_level = 3;
  auto still = Scene::create(relief::testing::pyrenees_store(), nullptr, o, clock_);
  ASSERT_TRUE(still) << still.error().message;
  auto f = (*still)->draw(orbit->camera(), *target_);
  ASSERT_TRUE(f) << f.error().message;
  EXPECT_TRUE(f->complete);
  EXPECT_EQ(f->draw.triangles, last->draw.triangles);
  EXPECT_EQ(*target_->read_rgba(), live);
}

}  // namespace
}  // namespace relief::view
