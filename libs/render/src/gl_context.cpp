#include <EGL/egl.h>
#include <EGL/eglext.h>

#include <string>

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

bool software_rasteriser() {
  const auto* name = reinterpret_cast<const char*>(glGetString(GL_RENDERER));
  const std::string renderer = name ? name : "";
  return renderer.find("llvmpipe") != std::string::npos ||
         renderer.find("softpipe") != std::string::npos;
}

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

}  // namespace relief::render
