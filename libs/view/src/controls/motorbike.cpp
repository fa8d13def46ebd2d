// Motorbike: riding on the ground with a speed (throttle and brake), steering
// that turns the heading while moving, and a lean into turns: the bank angle
// of a balanced turn, atan(speed * turn rate / g), reached at kLeanRate.
#include <algorithm>
#include <cmath>

#include "base.h"
#include "modes.h"

namespace relief::view::controls {
namespace {

class Motorbike final : public ControllerBase {
 public:
  Motorbike(const lod::Camera& start, const ControllerOptions& options)
      : ControllerBase(start, options), speed_(std::max(options.speed, 0.0)) {}
  ControlMode mode() const override { return ControlMode::motorbike; }

  static constexpr double kAcceleration = 6;  // m/s per second, throttle
  static constexpr double kBraking = 10;      // m/s per second
  static constexpr double kSteerRate = 40;    // degrees per second of heading
  static constexpr double kLeanRate = 90;     // degrees per second of roll
  static constexpr double kMaxLean = 50;      // degrees
  static constexpr double kLookRate = 30;     // degrees per second
  static constexpr double kGravity = 9.81;

 private:
  void on_jump() override { speed_ = 0; }

  void step(double dt, const Ground& ground) override {
    const int throttle = axis(Key::up, Key::down, Key::w, Key::s);
    speed_ += (throttle > 0 ? kAcceleration : throttle < 0 ? -kBraking : 0) * dt;
    speed_ = std::clamp(speed_, 0.0, options_.max_bike_speed);
    const double turn = speed_ > 0 ? axis(Key::right, Key::left, Key::d, Key::a) * kSteerRate : 0;
    camera_.heading = std::remainder(camera_.heading + turn * dt, 360.0);
    // Leaning right (into a right turn) lowers the right vector: roll < 0.
    const double lean =
        std::clamp(-std::atan(speed_ * turn * kDeg / kGravity) / kDeg, -kMaxLean, kMaxLean);
    const double d = std::clamp(lean - camera_.roll, -kLeanRate * dt, kLeanRate * dt);
    camera_.roll += d;
    camera_.pitch = std::clamp(camera_.pitch + axis(Key::page_up, Key::page_down) * kLookRate * dt,
                               -85.0, 85.0);
    camera_ = move_level(camera_, speed_ * dt, 0);
    camera_.height = ground_or_zero(ground, camera_.lon, camera_.lat) +
                     std::max(options_.bike_eye_height, options_.clearance);
  }

  double speed_;
};

}  // namespace

std::unique_ptr<Controller> make_motorbike(const lod::Camera& start,
                                           const ControllerOptions& options) {
  return std::make_unique<Motorbike>(start, options);
}

}  // namespace relief::view::controls
