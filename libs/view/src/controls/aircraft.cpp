// Aircraft: a throttle and a yoke. The throttle changes the speed; the yoke
// rolls (left and right arrows; the wings level again when released) and
// pitches (down arrow: nose up, like pulling a yoke); the roll turns the
// heading and the pitch climbs or dives along the direction of flight.
// Each step first changes the attitude, then flies with it.
#include <algorithm>
#include <cmath>

#include "base.h"
#include "modes.h"

namespace relief::view::controls {
namespace {

class Aircraft final : public ControllerBase {
 public:
  Aircraft(const lod::Camera& start, const ControllerOptions& options)
      : ControllerBase(start, options), speed_(std::max(options.speed, 0.0)) {}
  ControlMode mode() const override { return ControlMode::aircraft; }

  static constexpr double kRollRate = 45;   // degrees per second
  static constexpr double kMaxRoll = 60;    // degrees
  static constexpr double kPitchRate = 30;  // degrees per second
  static constexpr double kMaxPitch = 80;   // degrees
  static constexpr double kTurnRate = 90;   // degrees per second at 90 degrees of roll
  // Throttle: the speed grows by (kMinAcceleration + speed) per second, so it
  // spans walking pace to orbit in a few seconds.
  static constexpr double kMinAcceleration = 10;  // m/s per second

 private:
  void on_jump() override { speed_ = 0; }

  void step(double dt, const Ground&) override {
    const int throttle = axis(Key::page_up, Key::page_down, Key::w, Key::s);
    speed_ = std::max(0.0, speed_ + throttle * (kMinAcceleration + speed_) * dt);
    // Left raises the right wing (make_view: roll > 0 turns the right
    // vector up): a bank to the left, which turns left.
    const int roll = axis(Key::left, Key::right);
    if (roll) {
      camera_.roll = std::clamp(camera_.roll + roll * kRollRate * dt, -kMaxRoll, kMaxRoll);
    } else {  // wings level
      const double back = std::min(std::abs(camera_.roll), kRollRate * dt);
      camera_.roll -= std::copysign(back, camera_.roll);
    }
    const int pitch = axis(Key::down, Key::up);
    camera_.pitch = std::clamp(camera_.pitch + pitch * kPitchRate * dt, -kMaxPitch, kMaxPitch);
    camera_.heading -= kTurnRate * std::sin(camera_.roll * kDeg) * dt;
    camera_.heading = std::remainder(camera_.heading, 360.0);
    const double p = camera_.pitch * kDeg, distance = speed_ * dt;
    const double height = camera_.height + distance * std::sin(p);
    camera_ = move_level(camera_, distance * std::cos(p), 0);
    camera_.height = height;
  }

  double speed_;
};

}  // namespace

std::unique_ptr<Controller> make_aircraft(const lod::Camera& start,
                                          const ControllerOptions& options) {
  return std::make_unique<Aircraft>(start, options);
}

}  // namespace relief::view::controls
