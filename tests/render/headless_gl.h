#pragma once
// One headless GL context for a test binary, made on first use and current
// on the thread that made it (the GL tests run in one process: GL_IN_PROCESS).
#include <memory>
#include <stdexcept>

#include "relief/render/render_target.h"

namespace relief::render {

struct HeadlessGl {
  std::unique_ptr<GlContext> context;
  HeadlessGl() {
    auto c = GlContext::create_headless();
    if (!c) throw std::runtime_error(c.error().message);
    context = std::move(*c);
  }
};
inline HeadlessGl& headless_gl() {
  static HeadlessGl g;
  return g;
}

}  // namespace relief::render
