// Walking and riding over the real Pyrenees store, with the ground of the
// tiles resident (loading on as the frames draw): never below the ground.
#include "controls_input.h"
#include "loaded_scene.h"
#include "relief/view/ground.h"

namespace relief::view {
namespace {

class ControlsPyreneesTest : public testing::LoadedSceneTest {
 protected:
  // Drives `c` 60 s at 30 frames per second, steering right or left for
  // `turn_frames` every 10 s, drawing (and loading) every 300th frame; every
  // frame's eye is at least the clearance above the ground it was placed on.
  // With `max_slope_deg`, no step climbs steeper, and some were refused.
  void drive(Controller& c, double least_above, int turn_frames,
             std::optional<double> max_slope_deg = {}) {
    const Ground ground = resident_ground(*scene_);
    lod::Camera last = c.camera();
    double path = 0;
    int refused = 0;
    c.push(view::testing::key_down(Key::up));
    for (int frame = 0; frame < 1800; ++frame) {
      if (frame % 300 == 0) c.push(view::testing::key_down(frame % 600 ? Key::left : Key::right));
      if (frame % 300 == turn_frames) {
        c.push(view::testing::key_up(Key::left));
        c.push(view::testing::key_up(Key::right));
      }
      const lod::Camera& cam = c.update(1.0 / 30, ground);
      const double below = *ground(cam.lon, cam.lat);
      ASSERT_GE(cam.height, below + least_above - 1e-9) << frame;
      ASSERT_GE(cam.height, below + ControllerOptions{}.clearance) << frame;
      const double step =
          lod::length(lod::ecef(cam.lon, cam.lat, 0) - lod::ecef(last.lon, last.lat, 0));
      if (step == 0) ++refused;
      if (max_slope_deg && step > 0) {
        const double climb = below - *ground(last.lon, last.lat);
        ASSERT_LE(climb, std::tan(*max_slope_deg * 3.14159265358979323846 / 180) * step * 1.001)
            << frame;
      }
      path += step;
      last = cam;
      if (frame % 300 == 299) {  // more detail arrives (all of it: deterministic)
        draw(cam);
        wait_idle();
      }
    }
    EXPECT_GT(path, 300);  // it went somewhere over the mountains
    if (max_slope_deg) {
      EXPECT_GT(refused, 0);  // the limit was met
    }
  }
};

const lod::Camera kStart = [] {
  lod::Camera c;
  c.lon = 1.43, c.lat = 42.64, c.height = 3000, c.heading = -45, c.pitch = -5;
  c.width = 160, c.height_px = 120;
  return c;
}();

TEST_F(ControlsPyreneesTest, WalkNeverGoesBelowTheGround) {
  load(kStart);
  ControllerOptions o;
  o.walk_speed = 20;
  o.max_slope_deg = 20;  // (the path has slopes of 20 to 35 degrees to refuse)
  auto walker = make_controller(ControlMode::walk, kStart, o);
  drive(*walker, o.eye_height, 90, o.max_slope_deg);  // turns about where it is stopped
}

TEST_F(ControlsPyreneesTest, MotorbikeNeverGoesBelowTheGround) {
  load(kStart);
  ControllerOptions o;
  o.speed = 25;
  auto bike = make_controller(ControlMode::motorbike, kStart, o);
  drive(*bike, o.bike_eye_height, 30);
}

}  // namespace
}  // namespace relief::view
