#pragma once
// Scripted input for the control-mode tests: the events the window's
// callbacks produce, and a stepped clock.
#include <cmath>
#include <functional>

#include "relief/view/controller.h"

namespace relief::view::testing {

inline InputEvent key_down(Key k) {
  InputEvent e;
  e.type = InputEvent::Type::key_down;
  e.key = k;
  return e;
}
inline InputEvent key_up(Key k) {
  InputEvent e;
  e.type = InputEvent::Type::key_up;
  e.key = k;
  return e;
}
inline InputEvent cursor(double x, double y) {
  InputEvent e;
  e.type = InputEvent::Type::cursor;
  e.x = x;
  e.y = y;
  return e;
}
inline InputEvent button(bool down, MouseButton b = MouseButton::left) {
  InputEvent e;
  e.type = down ? InputEvent::Type::mouse_down : InputEvent::Type::mouse_up;
  e.button = b;
  return e;
}
inline InputEvent scroll(double notches) {
  InputEvent e;
  e.type = InputEvent::Type::scroll;
  e.y = notches;
  return e;
}

// Updates `c` for `seconds` in steps of `dt` (a whole number of them), calling
// `each` with the camera after every step.
inline void run(Controller& c, double seconds, double dt, const Ground& ground,
                const std::function<void(const lod::Camera&)>& each = {}) {
  const long steps = std::lround(seconds / dt);
  for (long i = 0; i < steps; ++i) {
    const lod::Camera& cam = c.update(dt, ground);
    if (each) each(cam);
  }
}

}  // namespace relief::view::testing
