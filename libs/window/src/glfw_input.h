#pragma once
// GLFW's key codes, buttons and modifiers as the viewer's input (view/input.h).
#include <utility>

#include "relief/view/input.h"

namespace relief::window {

view::Key key_from_glfw(int key);
uint8_t modifiers_from_glfw(int mods);
view::MouseButton button_from_glfw(int button);

// A cursor position in window coordinates (GLFW's) as framebuffer pixels
// (the frames'): scaled by framebuffer size over window size per axis, which
// is more than 1 on a HiDPI screen. A minimised window (size 0) keeps them.
std::pair<double, double> cursor_to_pixels(double x, double y, int window_width, int window_height,
                                           int framebuffer_width, int framebuffer_height);

}  // namespace relief::window
