#pragma once
// Input as the viewer's controllers see it, independent of the window
// system: the window's callbacks (GLFW) translate their events into these,
// and scripted tests feed the same events through the same path.
#include <cstdint>

namespace relief::view {

enum class Key : uint16_t {
  unknown,
  w,
  a,
  s,
  d,
  q,
  e,
  r,
  f,
  c,
  g,
  h,
  m,
  p,
  space,
  shift,
  control,
  up,
  down,
  left,
  right,
  page_up,
  page_down,
  home,
  plus,
  minus,
  escape,
  tab,
  enter,
  digit1,
  digit2,
  digit3,
  digit4,
  digit5,
  f1,
  f2,
  f3,
  f4,
  f5,
  f6,
  f7,
  f8,
  f9,
  f10,
  f11,
  f12,
};

enum Modifier : uint8_t { kShift = 1, kControl = 2, kAlt = 4 };

enum class MouseButton : uint8_t { left, right, middle };

struct InputEvent {
  enum class Type : uint8_t {
    key_down,
    key_up,
    mouse_down,
    mouse_up,
    cursor,  // x, y: cursor position, pixels, origin top-left
    scroll,  // x, y: scroll offsets (wheel: y, one notch = 1)
    resize,  // x, y: framebuffer width and height, pixels
  };
  Type type = Type::cursor;
  Key key = Key::unknown;                  // key events
  MouseButton button = MouseButton::left;  // mouse events
  uint8_t modifiers = 0;                   // Modifier bits
  double x = 0, y = 0;
};

}  // namespace relief::view
