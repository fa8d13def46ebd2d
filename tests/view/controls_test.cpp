// The control modes driven by scripted input (the events the window's
// callbacks make) over analytic ground, in steps of 1/60 s: each follows the
// trajectory its rules give, reports its speeds, and never goes below the
// ground + clearance.
#include <gtest/gtest.h>

#include <cmath>

#include "controls_input.h"
#include "relief/view/ground.h"

namespace relief::view {
namespace {

using namespace view::testing;

constexpr double kDt = 1.0 / 60;
constexpr double kDeg = 3.14159265358979323846 / 180;
constexpr double kMetresPerDegree = 111000;  // of the analytic grounds' slopes

Ground flat(double h) {
  return [h](double, double) -> std::optional<double> { return h; };
}
// A plane rising northwards at `slope_deg` (in metres per kMetresPerDegree).
Ground ramp(double slope_deg) {
  return [slope_deg](double, double lat) -> std::optional<double> {
    return 500 + (lat - 42.5) * kMetresPerDegree * std::tan(slope_deg * kDeg);
  };
}

lod::Camera level_camera(double height) {
  lod::Camera c;
  c.lon = 1.5, c.lat = 42.5, c.height = height;
  c.heading = 0, c.pitch = 0, c.roll = 0;
  return c;
}

double ground_distance(const lod::Camera& a, const lod::Camera& b) {
  return lod::length(lod::ecef(a.lon, a.lat, 0) - lod::ecef(b.lon, b.lat, 0));
}
// Over the ground at height `h` (moves are along the eye's height: at 200 m
// a metre there is 1 - 3e-5 metres on the ellipsoid).
double distance_at(const lod::Camera& a, const lod::Camera& b, double h) {
  return lod::length(lod::ecef(a.lon, a.lat, h) - lod::ecef(b.lon, b.lat, h));
}
double eye_distance(const lod::Camera& a, const lod::Camera& b) {
  return lod::length(lod::ecef(a.lon, a.lat, a.height) - lod::ecef(b.lon, b.lat, b.height));
}

TEST(ControlModes, NamesParseAndEveryModeIsMade) {
  for (auto m : {ControlMode::orbit, ControlMode::aircraft, ControlMode::walk,
                 ControlMode::motorbike, ControlMode::playback}) {
    EXPECT_EQ(parse_control_mode(to_string(m)), m);
    auto c = make_controller(m, level_camera(100));
    ASSERT_TRUE(c);
    EXPECT_EQ(c->mode(), m);
  }
  EXPECT_EQ(parse_control_mode("globe"), ControlMode::orbit);
  EXPECT_FALSE(parse_control_mode("helicopter"));
}

TEST(ControlModes, AircraftThrottleAndYokeFlyTheirRules) {
  ControllerOptions o;
  o.speed = 100;
  auto plane = make_controller(ControlMode::aircraft, level_camera(3000), o);
  const Ground ground = flat(0);
  // Level flight: 10 s at 100 m/s north.
  run(*plane, 10, kDt, ground);
  EXPECT_NEAR(eye_distance(plane->camera(), level_camera(3000)), 1000, 1e-3);
  EXPECT_NEAR(plane->camera().heading, 0, 1e-9);
  EXPECT_DOUBLE_EQ(plane->camera().height, 3000);
  EXPECT_NEAR(plane->linear_speed(), 100, 1e-6);
  EXPECT_LT(plane->angular_speed(), 0.01);  // the Earth's curvature only

  // Throttle 1 s: the speed grows by (10 + speed) per second, step by step.
  plane->push(key_down(Key::page_up));
  run(*plane, 1, kDt, ground);
  plane->push(key_up(Key::page_up));
  double speed = 100;
  for (int i = 0; i < 60; ++i) speed += (10 + speed) * kDt;
  EXPECT_NEAR(plane->linear_speed(), speed, 1e-6 * speed);

  // Yoke left: the roll grows 45 deg/s up to 60, and the roll turns the
  // heading at 90 sin(roll) deg/s.
  plane->push(key_down(Key::left));
  run(*plane, 2, kDt, ground);
  EXPECT_NEAR(plane->camera().roll, 60, 1e-9);
  const double heading = plane->camera().heading;
  run(*plane, 1, kDt, ground);
  EXPECT_NEAR(std::remainder(plane->camera().heading - heading, 360), -90 * std::sin(60 * kDeg),
              0.01);
  EXPECT_NEAR(plane->angular_speed(), 90 * std::sin(60 * kDeg), 0.5);
  plane->push(key_up(Key::left));
  run(*plane, 1.5, kDt, ground);  // the wings level at 45 deg/s
  EXPECT_EQ(plane->camera().roll, 0);

  // Down arrow (pulling the yoke) for 0.5 s: 15 degrees nose up; then the
  // flight climbs speed * sin(15 deg) per second.
  plane->push(key_down(Key::down));
  run(*plane, 0.5, kDt, ground);
  plane->push(key_up(Key::down));
  EXPECT_NEAR(plane->camera().pitch, 15, 1e-9);
  const double h0 = plane->camera().height;
  run(*plane, 10, kDt, ground);
  EXPECT_NEAR(plane->camera().height - h0, speed * std::sin(15 * kDeg) * 10, 1e-6);

  // Full dive: never below the ground + clearance, then along it.
  plane->push(key_down(Key::up));
  run(*plane, 60, kDt, ground, [&](const lod::Camera& c) { ASSERT_GE(c.height, o.clearance); });
  EXPECT_NEAR(plane->camera().pitch, -80, 1e-9);
  EXPECT_DOUBLE_EQ(plane->camera().height, o.clearance);
}

TEST(ControlModes, WalkFollowsTheGroundAndDoesNotClimbTooSteep) {
  ControllerOptions o;  // 1.5 m/s, eye 1.8 m, 35 degrees at most
  {
    const Ground ground = ramp(20);
    auto walker = make_controller(ControlMode::walk, level_camera(0), o);
    walker->push(key_down(Key::up));
    run(*walker, 10, kDt, ground,
        [&](const lod::Camera& c) { ASSERT_DOUBLE_EQ(c.height, *ground(c.lon, c.lat) + 1.8); });
    // At the eye's height, which climbed from 501.8 to 507.3 m.
    EXPECT_NEAR(distance_at(walker->camera(), level_camera(0), 504.5), 15, 1e-5);
    EXPECT_NEAR(walker->camera().heading, 0, 1e-9);
  }
  {
    const Ground ground = ramp(50);
    auto walker = make_controller(ControlMode::walk, level_camera(0), o);
    walker->push(key_down(Key::w));
    run(*walker, 2, kDt, ground);
    EXPECT_EQ(walker->camera().lat, 42.5);  // too steep: not one step up
    EXPECT_DOUBLE_EQ(walker->camera().height, *ground(1.5, 42.5) + 1.8);
    walker->push(key_up(Key::w));
    walker->push(key_down(Key::s));  // down it is fine
    run(*walker, 2, kDt, ground);
    EXPECT_NEAR(ground_distance(walker->camera(), level_camera(0)), 3, 1e-3);
    EXPECT_LT(walker->camera().lat, 42.5);
  }
  {
    auto walker = make_controller(ControlMode::walk, level_camera(0), o);
    walker->push(key_down(Key::left));
    run(*walker, 1, kDt, flat(0));
    EXPECT_NEAR(walker->camera().heading, -60, 1e-9);
    walker->push(key_up(Key::left));
    walker->push(key_down(Key::shift));
    walker->push(key_down(Key::up));
    run(*walker, 2, kDt, flat(0));  // running: four times the speed
    EXPECT_NEAR(ground_distance(walker->camera(), level_camera(0)), 12, 1e-3);
    EXPECT_NEAR(walker->linear_speed(), 6, 1e-6);
  }
}

TEST(ControlModes, MotorbikeRidesTheGroundAndLeansIntoTurns) {
  ControllerOptions o;
  {
    auto bike = make_controller(ControlMode::motorbike, level_camera(0), o);
    bike->push(key_down(Key::up));
    run(*bike, 5, kDt, flat(200),
        [&](const lod::Camera& c) { ASSERT_DOUBLE_EQ(c.height, 200 + o.bike_eye_height); });
    // 6 m/s per second for 300 steps: sum of 0.1 i m/s * dt.
    EXPECT_NEAR(distance_at(bike->camera(), level_camera(0), 201.2), 0.1 * kDt * 300 * 301 / 2,
                1e-6);
    EXPECT_NEAR(bike->linear_speed(), 30, 1e-6);
  }
  {
    o.speed = 10;
    auto bike = make_controller(ControlMode::motorbike, level_camera(0), o);
    bike->push(key_down(Key::right));
    run(*bike, 3, kDt, flat(0));
    EXPECT_NEAR(bike->camera().heading, 120, 1e-3);
    // The bank of a balanced turn: atan(v * omega / g), to the right (roll < 0).
    EXPECT_NEAR(bike->camera().roll, -std::atan(10 * 40 * kDeg / 9.81) / kDeg, 1e-9);
    bike->push(key_up(Key::right));
    run(*bike, 1, kDt, flat(0));
    EXPECT_EQ(bike->camera().roll, 0);
  }
  {
    const Ground hills = [](double lon, double lat) -> std::optional<double> {
      return 800 + 300 * std::sin(lat * 3000) * std::cos(lon * 2000);
    };
    o.speed = 30;
    auto bike = make_controller(ControlMode::motorbike, level_camera(0), o);
    bike->push(key_down(Key::left));
    run(*bike, 20, kDt, hills, [&](const lod::Camera& c) {
      ASSERT_DOUBLE_EQ(c.height, *hills(c.lon, c.lat) + o.bike_eye_height);
    });
  }
}

class OrbitTest : public ::testing::Test {
 protected:
  const Ground ground_ = flat(1000);
  const lod::Camera start_ = lod::look_at(1.5, 42.5, 1000, 20000, 30, -40, 60, 800, 600);
  std::unique_ptr<Controller> orbit_ = make_controller(ControlMode::orbit, start_);
};

TEST_F(OrbitTest, TheWheelZoomsTowardTheCursorWhichKeepsItsPoint) {
  const auto p = pick(start_, 600, 420, ground_);
  ASSERT_TRUE(p);
  const lod::Vec3 point = lod::ecef(p->lon, p->lat, p->height);
  double expected = p->distance;
  orbit_->push(cursor(600, 420));
  for (double notches : {1.0, 3.0, -2.0}) {
    orbit_->push(scroll(notches));
    orbit_->update(kDt, ground_);
    expected *= std::pow(0.8, notches);
    auto view = lod::make_view(orbit_->camera());
    ASSERT_TRUE(view);
    double sx = 0, sy = 0;
    ASSERT_TRUE(view->project(point, sx, sy));
    EXPECT_NEAR(sx, 600, 1e-6);
    EXPECT_NEAR(sy, 420, 1e-6);
    // (to 0.1 mm: the geodetic round trip of the eye)
    EXPECT_NEAR(lod::length(view->eye - point), expected, 1e-7 * expected);
  }
  // Zooming on and on stops above the ground.
  for (int i = 0; i < 60; ++i) {
    orbit_->push(scroll(1));
    ASSERT_GE(orbit_->update(kDt, ground_).height, 1000 + ControllerOptions{}.clearance);
  }
}

TEST_F(OrbitTest, DraggingRotatesAboutThePickedPoint) {
  const auto p = pick(start_, 400, 300, ground_);
  ASSERT_TRUE(p);
  const lod::Vec3 pivot = lod::ecef(p->lon, p->lat, p->height);
  for (const auto& e : {cursor(400, 300), button(true), cursor(440, 300), cursor(440, 320)}) {
    orbit_->push(e);
  }
  const lod::Camera& c = orbit_->update(kDt, ground_);
  // 0.25 degrees per pixel: 40 px right turns the view 10 degrees about the
  // point (the heading decreases), 20 px down lowers the view 5 degrees.
  EXPECT_NEAR(std::remainder(c.heading - start_.heading, 360), -10, 0.05);
  EXPECT_NEAR(c.pitch - start_.pitch, -5, 0.05);
  auto view = lod::make_view(c);
  ASSERT_TRUE(view);
  EXPECT_NEAR(lod::length(view->eye - pivot), p->distance, 1e-6 * p->distance);
  double sx = 0, sy = 0;
  ASSERT_TRUE(view->project(pivot, sx, sy));
  EXPECT_NEAR(sx, 400, 0.5);
  EXPECT_NEAR(sy, 300, 0.5);
  EXPECT_GT(orbit_->angular_speed(), 5 / kDt);
  // Moving the cursor after the release does nothing.
  orbit_->push(button(false));
  orbit_->push(cursor(500, 500));
  const lod::Camera before = orbit_->camera();
  orbit_->update(kDt, ground_);
  EXPECT_EQ(orbit_->camera().heading, before.heading);
  EXPECT_EQ(orbit_->linear_speed(), 0);
}

TEST_F(OrbitTest, DraggingAViewStraightDownTurnsItsHeading) {
  lod::Camera down = level_camera(11000);
  down.pitch = -90;
  orbit_->set_camera(down);
  for (const auto& e : {cursor(400, 300), button(true), cursor(440, 300)}) orbit_->push(e);
  const lod::Camera& c = orbit_->update(kDt, ground_);
  EXPECT_NEAR(c.heading, -10, 1e-6);
  EXPECT_NEAR(c.pitch, -90, 1e-6);
  EXPECT_EQ(c.roll, 0);
  EXPECT_NEAR(c.lon, down.lon, 1e-9);
  EXPECT_NEAR(c.lat, down.lat, 1e-9);
  EXPECT_NEAR(c.height, 11000, 1e-6);
}

TEST_F(OrbitTest, KeysPanAtTheHeightAboveTheGround) {
  const double above = start_.height - 1000;
  orbit_->push(key_down(Key::up));
  run(*orbit_, 1, kDt, ground_);
  EXPECT_NEAR(eye_distance(orbit_->camera(), start_), above, 1e-4 * above);
  // The same direction over the ground: the heading turns with the meridians
  // (13 km at 30 degrees and latitude 42.5: 0.054 degrees).
  EXPECT_NEAR(orbit_->camera().heading, start_.heading, 0.06);
  EXPECT_NEAR(orbit_->linear_speed(), above, 1e-4 * above);
}

TEST(ControlModes, AJumpResetsSpeedsAndAResizeChangesTheViewport) {
  ControllerOptions o;
  o.speed = 50;
  auto plane = make_controller(ControlMode::aircraft, level_camera(1000), o);
  run(*plane, 1, kDt, flat(0));
  EXPECT_GT(plane->linear_speed(), 0);
  plane->set_camera(level_camera(2000));
  EXPECT_EQ(plane->linear_speed(), 0);
  InputEvent r;
  r.type = InputEvent::Type::resize;
  r.x = 1280, r.y = 720;
  plane->push(r);
  plane->update(kDt, flat(0));
  EXPECT_EQ(plane->camera().width, 1280);
  EXPECT_EQ(plane->camera().height_px, 720);
  EXPECT_EQ(plane->camera().height, 2000);  // the jump stopped the aircraft
}

}  // namespace
}  // namespace relief::view
