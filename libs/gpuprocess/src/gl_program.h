#pragma once
// Owning handles of the GL objects the pipeline uses: compute programs and
// single-level R32F textures. Used on the thread that owns the GL context.
#include <string>
#include <utility>

#include "gl.h"
#include "relief/base/result.h"

namespace relief::gpuprocess {

class GlProgram {
 public:
  GlProgram() = default;
  explicit GlProgram(GLuint id) : id_(id) {}
  GlProgram(GlProgram&& o) noexcept : id_(std::exchange(o.id_, 0)) {}
  GlProgram& operator=(GlProgram&& o) noexcept {
    std::swap(id_, o.id_);
    return *this;
  }
  ~GlProgram();
  GLuint id() const { return id_; }

 private:
  GLuint id_ = 0;
};

// Compiles and links a compute shader; the error carries the GL log and `name`.
Result<GlProgram> compile_compute(const std::string& name, const std::string& source);

class GlTexture {
 public:
  GlTexture() = default;
  // Nearest, one level; R32F unless `internal_format` says otherwise.
  GlTexture(int width, int height, GLenum internal_format = GL_R32F);
  GlTexture(GlTexture&& o) noexcept
      : id_(std::exchange(o.id_, 0)), width_(o.width_), height_(o.height_) {}
  GlTexture& operator=(GlTexture&& o) noexcept {
    std::swap(id_, o.id_);
    std::swap(width_, o.width_);
    std::swap(height_, o.height_);
    return *this;
  }
  ~GlTexture();
  GLuint id() const { return id_; }
  int width() const { return width_; }
  int height() const { return height_; }

 private:
  GLuint id_ = 0;
  int width_ = 0, height_ = 0;
};

}  // namespace relief::gpuprocess
