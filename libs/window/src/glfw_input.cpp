#include "glfw_input.h"

#define GLFW_INCLUDE_NONE
#include <GLFW/glfw3.h>

namespace relief::window {

view::Key key_from_glfw(int key) {
  using view::Key;
  if (key >= GLFW_KEY_1 && key <= GLFW_KEY_5) {
    return static_cast<Key>(static_cast<int>(Key::digit1) + (key - GLFW_KEY_1));
  }
  if (key >= GLFW_KEY_F1 && key <= GLFW_KEY_F12) {
    return static_cast<Key>(static_cast<int>(Key::f1) + (key - GLFW_KEY_F1));
  }
  switch (key) {
    case GLFW_KEY_W:
      return Key::w;
    case GLFW_KEY_A:
      return Key::a;
    case GLFW_KEY_S:
      return Key::s;
    case GLFW_KEY_D:
      return Key::d;
    case GLFW_KEY_Q:
      return Key::q;
    case GLFW_KEY_E:
      return Key::e;
    case GLFW_KEY_R:
      return Key::r;
    case GLFW_KEY_F:
      return Key::f;
    case GLFW_KEY_C:
      return Key::c;
    case GLFW_KEY_G:
      return Key::g;
    case GLFW_KEY_H:
      return Key::h;
    case GLFW_KEY_M:
      return Key::m;
    case GLFW_KEY_P:
      return Key::p;
    case GLFW_KEY_SPACE:
      return Key::space;
    case GLFW_KEY_LEFT_SHIFT:
    case GLFW_KEY_RIGHT_SHIFT:
      return Key::shift;
    case GLFW_KEY_LEFT_CONTROL:
    case GLFW_KEY_RIGHT_CONTROL:
      return Key::control;
    case GLFW_KEY_UP:
      return Key::up;
    case GLFW_KEY_DOWN:
      return Key::down;
    case GLFW_KEY_LEFT:
      return Key::left;
    case GLFW_KEY_RIGHT:
      return Key::right;
    case GLFW_KEY_PAGE_UP:
      return Key::page_up;
    case GLFW_KEY_PAGE_DOWN:
      return Key::page_down;
    case GLFW_KEY_HOME:
      return Key::home;
    case GLFW_KEY_EQUAL:  // '+' shares the key with '=' on most layouts
    case GLFW_KEY_KP_ADD:
      return Key::plus;
    case GLFW_KEY_MINUS:
    case GLFW_KEY_KP_SUBTRACT:
      return Key::minus;
    case GLFW_KEY_ESCAPE:
      return Key::escape;
    case GLFW_KEY_TAB:
      return Key::tab;
    case GLFW_KEY_ENTER:
    case GLFW_KEY_KP_ENTER:
      return Key::enter;
    default:
      return Key::unknown;
  }
}

uint8_t modifiers_from_glfw(int mods) {
  uint8_t m = 0;
  if (mods & GLFW_MOD_SHIFT) m |= view::kShift;
  if (mods & GLFW_MOD_CONTROL) m |= view::kControl;
  if (mods & GLFW_MOD_ALT) m |= view::kAlt;
  return m;
}

view::MouseButton button_from_glfw(int button) {
  switch (button) {
    case GLFW_MOUSE_BUTTON_RIGHT:
      return view::MouseButton::right;
    case GLFW_MOUSE_BUTTON_MIDDLE:
      return view::MouseButton::middle;
    default:
      return view::MouseButton::left;
  }
}

std::pair<double, double> cursor_to_pixels(double x, double y, int window_width, int window_height,
                                           int framebuffer_width, int framebuffer_height) {
  if (window_width > 0 && framebuffer_width > 0)
    x *= static_cast<double>(framebuffer_width) / window_width;
  if (window_height > 0 && framebuffer_height > 0)
    y *= static_cast<double>(framebuffer_height) / window_height;
  return {x, y};
}

}  // namespace relief::window
