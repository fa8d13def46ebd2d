// Walk: the eye at eye_height above the ground, following it; forward and
// back, sideways, turning and looking up or down; a step that would climb
// steeper than max_slope_deg is not taken.
#include <algorithm>
#include <cmath>

#include "base.h"
#include "modes.h"

namespace relief::view::controls {
namespace {

class Walk final : public ControllerBase {
 public:
  using ControllerBase::ControllerBase;
  ControlMode mode() const override { return ControlMode::walk; }

  static constexpr double kRunFactor = 4;  // shift held
  static constexpr double kTurnRate = 60;  // degrees per second
  static constexpr double kLookRate = 30;  // degrees per second
  static constexpr double kMaxLook = 85;   // degrees up or down

 private:
  void step(double dt, const Ground& ground) override {
    camera_.heading =
        std::remainder(camera_.heading + axis(Key::right, Key::left) * kTurnRate * dt, 360.0);
    camera_.pitch = std::clamp(camera_.pitch + axis(Key::page_up, Key::page_down) * kLookRate * dt,
                               -kMaxLook, kMaxLook);
    camera_.roll = 0;
    const int ahead = axis(Key::up, Key::down, Key::w, Key::s), side = axis(Key::d, Key::a);
    const double here = ground_or_zero(ground, camera_.lon, camera_.lat);
    if (ahead || side) {
      const double d = options_.walk_speed * (held(Key::shift) ? kRunFactor : 1) * dt;
      const double n = std::hypot(ahead, side);
      const lod::Camera next = move_level(camera_, ahead * d / n, side * d / n);
      const double there = ground_or_zero(ground, next.lon, next.lat);
      if (there - here <= std::tan(options_.max_slope_deg * kDeg) * d) {
        camera_ = next;
        camera_.height = there + eye();
        return;
      }
    }
    camera_.height = here + eye();
  }

  double eye() const { return std::max(options_.eye_height, options_.clearance); }
};

}  // namespace

std::unique_ptr<Controller> make_walk(const lod::Camera& start, const ControllerOptions& options) {
  return std::make_unique<Walk>(start, options);
}

}  // namespace relief::view::controls
