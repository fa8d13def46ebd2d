// Walking and riding over the real Pyrenees store, with the ground of the
// tiles resident (loading on as the frames draw): never below the ground.
#include "controls_input.h"
#include "loaded_scene.h"
#include "relief/view/ground.h"

namespace relief::view {
namespace {

class ControlsPyreneesTest : public testing::LoadedSceneTest {
 protected:
  // Drives `c` 60 s at 30 frames per second, steering left and right
  // a while, drawing every 300th frame; every frame's eye is at least the
  // clearance above the ground it was placed on.
  void drive(Controller& c, double least_above) {
    const Ground ground = resident_ground(*scene_);
    lod::Camera last = c.camera();
    double path = 0;
    c.push(view::testing::key_down(Key::up));
    for (int frame = 0; frame < 1800; ++frame) {
      if (frame % 300 == 0) c.push(view::testing::key_down(frame % 600 ? Key::left : Key::right));
      if (frame % 300 == 30) {
        c.push(view::testing::key_up(Key::left));
        c.push(view::testing::key_up(Key::right));
      }
      const lod::Camera& cam = c.update(1.0 / 30, ground);
      const double below = *ground(cam.lon, cam.lat);
      ASSERT_GE(cam.height, below + least_above - 1e-9) << frame;
      ASSERT_GE(cam.height, below + ControllerOptions{}.clearance) << frame;
      path += lod::length(lod::ecef(cam.lon, cam.lat, 0) - lod::ecef(last.lon, last.lat, 0));
      last = cam;
      if (frame % 300 == 299) draw(cam);
    }
    EXPECT_GT(path, 300);  // it went somewhere over the mountains
  }
};

const lod::Camera kStart = [] {
  lod::Camera c;
  c.lon = 1.43, c.lat = 42.64, c.height = 3000, c.heading = 60, c.pitch = -5;
  c.width = 160, c.height_px = 120;
  return c;
}();

TEST_F(ControlsPyreneesTest, WalkNeverGoesBelowTheGround) {
  load(kStart);
  ControllerOptions o;
  o.walk_speed = 20;
  auto walker = make_controller(ControlMode::walk, kStart, o);
  drive(*walker, o.eye_height);
}

TEST_F(ControlsPyreneesTest, MotorbikeNeverGoesBelowTheGround) {
  load(kStart);
  ControllerOptions o;
  o.speed = 25;
  auto bike = make_controller(ControlMode::motorbike, kStart, o);
  drive(*bike, o.bike_eye_height);
}

}  // namespace
}  // namespace relief::view
