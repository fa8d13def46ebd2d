#include "base.h"

#include <algorithm>
#include <cmath>

namespace relief::view::controls {

namespace {

double angle_between(const lod::Vec3& a, const lod::Vec3& b) {
  return std::atan2(lod::length(lod::cross(a, b)), lod::dot(a, b));
}

}  // namespace

int ControllerBase::axis(Key plus, Key minus, Key plus2, Key minus2) const {
  const bool p = held(plus) || (plus2 != Key::unknown && held(plus2));
  const bool m = held(minus) || (minus2 != Key::unknown && held(minus2));
  return (p ? 1 : 0) - (m ? 1 : 0);
}

const lod::Camera& ControllerBase::update(double dt, const Ground& ground) {
  const Frame before = frame_of(camera_);
  std::vector<InputEvent> events;
  events.swap(queue_);
  for (const InputEvent& e : events) {
    on_event(e, ground);
    switch (e.type) {
      case InputEvent::Type::key_down:
      case InputEvent::Type::key_up:
        if (static_cast<size_t>(e.key) < keys_.size()) {
          keys_[static_cast<size_t>(e.key)] = e.type == InputEvent::Type::key_down;
        }
        break;
      case InputEvent::Type::mouse_down:
      case InputEvent::Type::mouse_up:
        buttons_[static_cast<size_t>(e.button)] = e.type == InputEvent::Type::mouse_down;
        break;
      case InputEvent::Type::cursor:
        cursor_x_ = e.x;
        cursor_y_ = e.y;
        break;
      case InputEvent::Type::resize:
        if (e.x >= 1 && e.y >= 1) {
          camera_.width = static_cast<int>(e.x);
          camera_.height_px = static_cast<int>(e.y);
        }
        break;
      case InputEvent::Type::scroll:
        break;
    }
  }
  jumped_ = false;
  step(dt, ground);
  camera_.height = std::max(camera_.height, least_height(ground, camera_.lon, camera_.lat));
  const Frame after = frame_of(camera_);
  if (jumped_) {
    linear_speed_ = angular_speed_ = 0;
  } else if (dt > 0) {
    linear_speed_ = lod::length(after.eye - before.eye) / dt;
    const double turn =
        std::max(angle_between(before.forward, after.forward), angle_between(before.up, after.up));
    angular_speed_ = turn / kDeg / dt;
  }
  return camera_;
}

void ControllerBase::set_camera(const lod::Camera& camera) {
  camera_ = camera;
  linear_speed_ = angular_speed_ = 0;
  on_jump();
}

}  // namespace relief::view::controls
