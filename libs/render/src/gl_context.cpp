#include <EGL/egl.h>
#include <EGL/eglext.h>

#include <fmt/format.h>

#include "gl.h"
#include "relief/render/render_target.h"

namespace relief::render {
namespace {

class EglContext final : public GlContext {
 public:
  EglContext(EGLDisplay d, EGLContext c) : display_(d), context_(c) {}
  ~EglContext() override {
    eglMakeCurrent(display_, EGL_NO_SURFACE, EGL_NO_SURFACE, EGL_NO_CONTEXT);
    eglDestroyContext(display_, context_);
    eglTerminate(display_);
    eglReleaseThread();  // the thread's EGL state, or it outlives the context
  }
  std::string renderer() const override {
    return fmt::format("{} ({})", reinterpret_cast<const char*>(glGetString(GL_RENDERER)),
                       reinterpret_cast<const char*>(glGetString(GL_VERSION)));
  }

 private:
  EGLDisplay display_;
  EGLContext context_;
};

}  // namespace

Result<std::unique_ptr<GlContext>> GlContext::create_headless() {
  auto get_display = reinterpret_cast<PFNEGLGETPLATFORMDISPLAYEXTPROC>(
      eglGetProcAddress("eglGetPlatformDisplayEXT"));
  if (!get_display)
    return fail("EGL: no eglGetPlatformDisplayEXT (is libEGL from Mesa installed?)");
  EGLDisplay display = get_display(EGL_PLATFORM_SURFACELESS_MESA, EGL_DEFAULT_DISPLAY, nullptr);
  EGLint major = 0, minor = 0;
  if (display == EGL_NO_DISPLAY || !eglInitialize(display, &major, &minor)) {
    return fail(
        fmt::format("EGL: cannot initialise a surfaceless display (error 0x{:x})", eglGetError()));
  }
  if (!eglBindAPI(EGL_OPENGL_API)) return fail("EGL: no desktop OpenGL");
  const EGLint config_attributes[] = {EGL_RENDERABLE_TYPE, EGL_OPENGL_BIT, EGL_NONE};
  EGLConfig config = nullptr;
  EGLint configs = 0;
  eglChooseConfig(display, config_attributes, &config, 1, &configs);
  const EGLint context_attributes[] = {EGL_CONTEXT_MAJOR_VERSION,
                                       4,
                                       EGL_CONTEXT_MINOR_VERSION,
                                       5,
                                       EGL_CONTEXT_OPENGL_PROFILE_MASK,
                                       EGL_CONTEXT_OPENGL_CORE_PROFILE_BIT,
                                       EGL_NONE};
  EGLContext context = eglCreateContext(display, configs ? config : EGL_NO_CONFIG_KHR,
                                        EGL_NO_CONTEXT, context_attributes);
  if (context == EGL_NO_CONTEXT) {
    eglTerminate(display);
    return fail(fmt::format("EGL: no OpenGL 4.5 core context (error 0x{:x})", eglGetError()));
  }
  if (!eglMakeCurrent(display, EGL_NO_SURFACE, EGL_NO_SURFACE, context)) {
    eglDestroyContext(display, context);
    eglTerminate(display);
    return fail("EGL: cannot make the context current without a surface");
  }
  return std::unique_ptr<GlContext>(new EglContext(display, context));
}

std::string gl_error() {
  const GLenum e = glGetError();
  return e == GL_NO_ERROR ? std::string() : fmt::format("GL error 0x{:x}", e);
}

namespace {
// The compile or link log of a shader or program.
std::string info_log(GLuint id, bool program) {
  char log[4096] = {};
  if (program) {
    glGetProgramInfoLog(id, sizeof log, nullptr, log);
  } else {
    glGetShaderInfoLog(id, sizeof log, nullptr, log);
  }
  return log;
}
}  // namespace

Result<GLuint> link_program(const char* vertex_source, const char* fragment_source) {
  auto compile = [](GLenum type, const char* source) -> Result<GLuint> {
    const GLuint s = glCreateShader(type);
    glShaderSource(s, 1, &source, nullptr);
    glCompileShader(s);
    GLint ok = 0;
    glGetShaderiv(s, GL_COMPILE_STATUS, &ok);
    if (!ok) {
      const std::string log = info_log(s, false);
      glDeleteShader(s);
      return fail("GLSL: " + log);
    }
    return s;
  };
  const GLuint vs = RELIEF_TRY(compile(GL_VERTEX_SHADER, vertex_source));
  const GLuint fs = RELIEF_TRY(compile(GL_FRAGMENT_SHADER, fragment_source));
  const GLuint p = glCreateProgram();
  glAttachShader(p, vs);
  glAttachShader(p, fs);
  glLinkProgram(p);
  glDeleteShader(vs);
  glDeleteShader(fs);
  GLint ok = 0;
  glGetProgramiv(p, GL_LINK_STATUS, &ok);
  if (!ok) {
    const std::string log = info_log(p, true);
    glDeleteProgram(p);
    return fail("GLSL link: " + log);
  }
  return p;
}

}  // namespace relief::render
