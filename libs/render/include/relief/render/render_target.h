#pragma once
// Where frames go. The renderer draws into a RenderTarget; the headless one
// is an offscreen framebuffer read back to memory, a window target (GLFW)
// comes with the viewer. Targets are used on the thread that owns the GL
// context only.
#include <cstdint>
#include <memory>
#include <vector>

#include "relief/base/result.h"

namespace relief::render {

class RenderTarget {
 public:
  virtual ~RenderTarget() = default;
  virtual int width() const = 0;
  virtual int height() const = 0;
  // Makes the target the destination of draw calls (framebuffer and viewport).
  virtual void bind() = 0;
  // RGBA8 pixels, top row first.
  virtual Result<std::vector<uint8_t>> read_rgba() = 0;
  // RGBA8 pixels, bottom row first (as GL stores them), into `out`, resized
  // to width * height * 4 (a buffer of that size is reused as it is): for a
  // consumer that flips rows itself (the movie encoder) and recycles buffers.
  virtual Status read_rgba_bottom_up(std::vector<uint8_t>& out);
  // Depth, top row first: reversed-Z, 1 at the near plane, 0 where nothing
  // was drawn (sort-last compositing). Targets without a readable depth
  // buffer fail.
  virtual Result<std::vector<float>> read_depth() { return fail("this target has no depth"); }
};

// A headless GL context (EGL, surfaceless: Mesa's llvmpipe without a GPU, the
// vendor driver with one), current on the calling thread, which owns it.
class GlContext {
 public:
  static Result<std::unique_ptr<GlContext>> create_headless();
  virtual ~GlContext() = default;
  virtual std::string renderer() const = 0;  // GL_RENDERER and GL_VERSION
};

// Whether the GL context current on this thread rasterises on the CPU (Mesa's
// llvmpipe or softpipe): its textures are main memory, so the GPU cache (L3)
// counts against a memory budget (view/memory_budget.h).
bool software_rasteriser();

// An offscreen framebuffer: RGBA8 colour and a 32-bit float depth buffer
// (reversed-Z). Needs a current GL context.
Result<std::unique_ptr<RenderTarget>> make_offscreen_target(int width, int height);

}  // namespace relief::render
