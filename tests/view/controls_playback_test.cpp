// Record and play back: the cameras of a scripted flight, taken every frame
// with the controller's own time, written as a path file and read back, are
// played back by the playback mode to 1e-9 with the same frame steps.
#include <gtest/gtest.h>

#include "../support/test_support.h"
#include "controls_input.h"
#include "relief/view/path_file.h"

namespace relief::view {
namespace {

using namespace view::testing;

TEST(ControlsPlayback, ARecordedFlightPlaysBackToTheNanometre) {
  lod::Camera start;
  start.lon = 1.4, start.lat = 42.6, start.height = 4000;
  start.heading = 30, start.pitch = -5, start.fov_y = 50, start.width = 320, start.height_px = 200;
  ControllerOptions o;
  o.speed = 150;
  auto plane = make_controller(ControlMode::aircraft, start, o);
  const Ground ground = [](double lon, double lat) -> std::optional<double> {
    return 2000 + 800 * std::sin(lat * 500) * std::sin(lon * 700);
  };
  // Uneven frame steps, as a window's are.
  auto dt_of = [](int frame) { return frame % 3 == 0 ? 1.0 / 30 : 1.0 / 60 + frame * 1e-5; };
  PathFile recorded;
  recorded.fps = 60;
  double time = 0;
  recorded.keyframes.push_back({time, plane->camera(), false});
  for (int frame = 0; frame < 400; ++frame) {
    if (frame == 20) plane->push(key_down(Key::left));
    if (frame == 90) plane->push(key_up(Key::left));
    if (frame == 100) plane->push(key_down(Key::down));
    if (frame == 130) plane->push(key_up(Key::down));
    if (frame == 200) plane->push(key_down(Key::page_up));
    if (frame == 260) plane->push(key_down(Key::up));
    const double dt = dt_of(frame);
    time += dt;
    recorded.keyframes.push_back({time, plane->update(dt, ground), false});
  }
  relief::testing::ScratchDir dir("controls_playback");
  const std::string file = (dir / "flight.json").string();
  ASSERT_TRUE(write_path_file(file, recorded));
  auto read = read_path_file(file, [&](const std::string&, const std::vector<double>& v) {
    lod::Camera c = start;
    c.lon = v[0], c.lat = v[1], c.height = v[2], c.heading = v[3], c.pitch = v[4], c.roll = v[5];
    return Result<lod::Camera>(c);
  });
  ASSERT_TRUE(read) << read.error().message;
  ASSERT_EQ(read->keyframes.size(), recorded.keyframes.size());

  ControllerOptions play;
  play.path = read->keyframes;
  auto player = make_controller(ControlMode::playback, start, play);
  auto same = [](const lod::Camera& a, const lod::Camera& b) {
    EXPECT_NEAR(a.lon, b.lon, 1e-9);
    EXPECT_NEAR(a.lat, b.lat, 1e-9);
    EXPECT_NEAR(a.height, b.height, 1e-9);
    EXPECT_NEAR(a.heading, b.heading, 1e-9);
    EXPECT_NEAR(a.pitch, b.pitch, 1e-9);
    EXPECT_NEAR(a.roll, b.roll, 1e-9);
    EXPECT_EQ(a.width, b.width);
    EXPECT_EQ(a.fov_y, b.fov_y);
  };
  same(player->camera(), recorded.keyframes[0].camera);
  for (int frame = 0; frame < 400; ++frame) {
    ASSERT_FALSE(player->finished()) << frame;
    SCOPED_TRACE(frame);
    same(player->update(dt_of(frame), ground), recorded.keyframes[frame + 1].camera);
  }
  EXPECT_TRUE(player->finished());
  EXPECT_GT(player->linear_speed(), 100);  // speeds are the path's
}

TEST(ControlsPlayback, ACutIsAJumpWithNoSpeed) {
  lod::Camera a;
  a.lon = 1.4, a.lat = 42.6, a.height = 3000;
  lod::Camera b = a;
  b.lon = 1.6;
  ControllerOptions o;
  o.path = {{0, a, false}, {1, a, false}, {1.5, b, true}, {2, b, false}};
  auto player = make_controller(ControlMode::playback, a, o);
  const Ground ground = [](double, double) -> std::optional<double> { return 0.0; };
  for (int frame = 0; frame < 8; ++frame) {
    const lod::Camera& c = player->update(0.25, ground);
    EXPECT_EQ(c.lon, frame < 5 ? 1.4 : 1.6) << frame;  // the sixth step reaches 1.5 s
    EXPECT_EQ(player->linear_speed(), 0) << frame;
  }
  EXPECT_TRUE(player->finished());
}

}  // namespace
}  // namespace relief::view
