#include "relief/render/overlay.h"

#include <vector>

#include "gl_backend.h"

namespace relief::render {
namespace {

// Pixel coordinates to clip space in the shader (y down to y up).
constexpr const char* kVertex = R"(#version 450 core
layout(location = 0) in vec2 pixel;
layout(location = 1) in vec4 colour;
uniform vec2 size;
out vec4 line_colour;
void main() {
  line_colour = colour;
  gl_Position = vec4(2.0 * pixel.x / size.x - 1.0, 1.0 - 2.0 * pixel.y / size.y, 0.0, 1.0);
}
)";

constexpr const char* kFragment = R"(#version 450 core
in vec4 line_colour;
out vec4 fragment;
void main() { fragment = line_colour; }
)";

struct LineVertex {
  float x, y;
  uint8_t rgba[4];
};

class GlOverlay final : public Overlay {
 public:
  Status init() {
    program_ = RELIEF_TRY(gl::Program::link(kVertex, kFragment));
    vao_.attribute(0, 0, 2, GL_FLOAT, offsetof(LineVertex, x));
    glVertexArrayAttribFormat(vao_.id(), 1, 4, GL_UNSIGNED_BYTE, GL_TRUE,
                              offsetof(LineVertex, rgba));
    glEnableVertexArrayAttrib(vao_.id(), 1);
    glVertexArrayAttribBinding(vao_.id(), 1, 0);
    if (auto e = gl_error(); !e.empty()) return fail("overlay setup: " + e);
    return {};
  }

  Status draw(std::span<const OverlayLine> lines, RenderTarget& target) override {
    if (lines.empty()) return {};
    vertices_.clear();
    for (const OverlayLine& l : lines) {
      // Pixel centres: a line from pixel (i, j) starts at (i + 0.5, j + 0.5).
      vertices_.push_back({l.x0 + 0.5f, l.y0 + 0.5f, {l.rgba[0], l.rgba[1], l.rgba[2], l.rgba[3]}});
      vertices_.push_back({l.x1 + 0.5f, l.y1 + 0.5f, {l.rgba[0], l.rgba[1], l.rgba[2], l.rgba[3]}});
    }
    gl::Uploads ignored;
    buffer_.write(vertices_.data(), vertices_.size() * sizeof(LineVertex), ignored);
    target.bind();
    glDisable(GL_DEPTH_TEST);
    glDisable(GL_CULL_FACE);
    glEnable(GL_BLEND);
    glBlendFunc(GL_SRC_ALPHA, GL_ONE_MINUS_SRC_ALPHA);
    glUseProgram(program_.id());
    glUniform2f(program_.location("size"), static_cast<float>(target.width()),
                static_cast<float>(target.height()));
    glBindVertexArray(vao_.id());
    glVertexArrayVertexBuffer(vao_.id(), 0, buffer_.id(), 0, sizeof(LineVertex));
    glDrawArrays(GL_LINES, 0, static_cast<GLsizei>(vertices_.size()));
    glDisable(GL_BLEND);
    glFinish();
    if (auto e = gl_error(); !e.empty()) return fail("drawing the overlay: " + e);
    return {};
  }

 private:
  gl::Program program_;
  gl::VertexArray vao_;
  gl::Buffer buffer_;
  std::vector<LineVertex> vertices_;
};

}  // namespace

Result<std::unique_ptr<Overlay>> Overlay::create() {
  auto o = std::make_unique<GlOverlay>();
  RELIEF_CHECK(o->init());
  return std::unique_ptr<Overlay>(std::move(o));
}

}  // namespace relief::render
