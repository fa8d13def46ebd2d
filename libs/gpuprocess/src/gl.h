#pragma once
// OpenGL 4.5 core declarations (libglvnd's libOpenGL exports every entry
// point), as in libs/render/src/gl.h; GL names stay inside this module's src/.
#define GL_GLEXT_PROTOTYPES 1
#include <GL/glcorearb.h>
