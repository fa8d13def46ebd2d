#pragma once
// OpenGL 4.5 core declarations (libglvnd's libOpenGL exports every entry point).
#define GL_GLEXT_PROTOTYPES 1
#include <GL/glcorearb.h>

#include <string>

#include "relief/base/result.h"

namespace relief::render {

// Compiles and links a program; errors carry the GLSL log.
Result<GLuint> link_program(const char* vertex_source, const char* fragment_source);
// The first GL error since the last call, as a message, or empty.
std::string gl_error();

}  // namespace relief::render
