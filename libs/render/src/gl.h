#pragma once
// OpenGL 4.5 core declarations (libglvnd's libOpenGL exports every entry point).
#define GL_GLEXT_PROTOTYPES 1
#include <GL/glcorearb.h>

#include <string>

namespace relief::render {

// The first GL error since the last call, as a message, or empty.
std::string gl_error();

}  // namespace relief::render
