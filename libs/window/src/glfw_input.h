#pragma once
// GLFW's key codes, buttons and modifiers as the viewer's input (view/input.h).
#include "relief/view/input.h"

namespace relief::window {

view::Key key_from_glfw(int key);
uint8_t modifiers_from_glfw(int mods);
view::MouseButton button_from_glfw(int button);

}  // namespace relief::window
