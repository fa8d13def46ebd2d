#include <algorithm>

#include <fmt/format.h>

#include "gl.h"
#include "relief/render/render_target.h"

namespace relief::render {
namespace {

class OffscreenTarget final : public RenderTarget {
 public:
  OffscreenTarget(int w, int h) : width_(w), height_(h) {
    glCreateFramebuffers(1, &fbo_);
    glCreateRenderbuffers(1, &colour_);
    glNamedRenderbufferStorage(colour_, GL_RGBA8, w, h);
    glCreateRenderbuffers(1, &depth_);
    glNamedRenderbufferStorage(depth_, GL_DEPTH_COMPONENT32F, w, h);
    glNamedFramebufferRenderbuffer(fbo_, GL_COLOR_ATTACHMENT0, GL_RENDERBUFFER, colour_);
    glNamedFramebufferRenderbuffer(fbo_, GL_DEPTH_ATTACHMENT, GL_RENDERBUFFER, depth_);
  }
  ~OffscreenTarget() override {
    glDeleteFramebuffers(1, &fbo_);
    glDeleteRenderbuffers(1, &colour_);
    glDeleteRenderbuffers(1, &depth_);
  }
  bool complete() const {
    return glCheckNamedFramebufferStatus(fbo_, GL_FRAMEBUFFER) == GL_FRAMEBUFFER_COMPLETE;
  }
  int width() const override { return width_; }
  int height() const override { return height_; }
  void bind() override {
    glBindFramebuffer(GL_FRAMEBUFFER, fbo_);
    glViewport(0, 0, width_, height_);
  }
  Status read_rgba_bottom_up(std::vector<uint8_t>& out) override {
    out.resize(static_cast<size_t>(width_) * height_ * 4);
    glBindFramebuffer(GL_READ_FRAMEBUFFER, fbo_);
    glPixelStorei(GL_PACK_ALIGNMENT, 1);
    glReadPixels(0, 0, width_, height_, GL_RGBA, GL_UNSIGNED_BYTE, out.data());
    if (auto e = gl_error(); !e.empty()) return fail("reading the frame: " + e);
    return {};
  }
  Result<std::vector<uint8_t>> read_rgba() override {
    std::vector<uint8_t> bottom_up;
    RELIEF_CHECK(read_rgba_bottom_up(bottom_up));
    std::vector<uint8_t> out(bottom_up.size());
    const size_t row = static_cast<size_t>(width_) * 4;
    for (int y = 0; y < height_; ++y) {
      std::copy_n(&bottom_up[static_cast<size_t>(height_ - 1 - y) * row], row,
                  &out[static_cast<size_t>(y) * row]);
    }
    return out;
  }
  Result<std::vector<float>> read_depth() override {
    std::vector<float> bottom_up(static_cast<size_t>(width_) * height_);
    glBindFramebuffer(GL_READ_FRAMEBUFFER, fbo_);
    glPixelStorei(GL_PACK_ALIGNMENT, 4);
    glReadPixels(0, 0, width_, height_, GL_DEPTH_COMPONENT, GL_FLOAT, bottom_up.data());
    if (auto e = gl_error(); !e.empty()) return fail("reading the depth: " + e);
    std::vector<float> out(bottom_up.size());
    const size_t row = static_cast<size_t>(width_);
    for (int y = 0; y < height_; ++y) {
      std::copy_n(&bottom_up[static_cast<size_t>(height_ - 1 - y) * row], row,
                  &out[static_cast<size_t>(y) * row]);
    }
    return out;
  }

 private:
  int width_, height_;
  GLuint fbo_ = 0, colour_ = 0, depth_ = 0;
};

}  // namespace

Status RenderTarget::read_rgba_bottom_up(std::vector<uint8_t>& out) {
  const std::vector<uint8_t> top_down = RELIEF_TRY(read_rgba());
  out.resize(top_down.size());
  const size_t row = static_cast<size_t>(width()) * 4;
  for (int y = 0; y < height(); ++y) {
    std::copy_n(&top_down[static_cast<size_t>(height() - 1 - y) * row], row,
                &out[static_cast<size_t>(y) * row]);
  }
  return {};
}

Result<std::unique_ptr<RenderTarget>> make_offscreen_target(int width, int height) {
  auto t = std::make_unique<OffscreenTarget>(width, height);
  if (!t->complete()) return fail(fmt::format("cannot create a {}x{} framebuffer", width, height));
  return std::unique_ptr<RenderTarget>(std::move(t));
}

}  // namespace relief::render
