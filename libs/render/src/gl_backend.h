#pragma once
// A thin OpenGL 4.5 backend: owning handles for buffers, texture arrays,
// vertex arrays and programs, and the count of bytes sent to the GPU. Shared
// by every renderer of this library (offscreen stills, the window target, the
// cluster renderer); all of it is used on the thread that owns the GL context.
#include <cstdint>
#include <string>
#include <unordered_map>
#include <vector>

#include "gl.h"
#include "relief/base/result.h"

namespace relief::render::gl {

// Bytes copied from the CPU to the GPU, by kind, since the last reset.
struct Uploads {
  uint64_t geometry = 0;  // vertices, indices, per-quad records, draw commands
  uint64_t textures = 0;  // tile data
};

// A buffer object. Static buffers are written once; dynamic ones grow on
// demand and can be rewritten in place.
class Buffer {
 public:
  Buffer() = default;
  ~Buffer();
  Buffer(Buffer&& o) noexcept;
  Buffer& operator=(Buffer&& o) noexcept;
  Buffer(const Buffer&) = delete;
  Buffer& operator=(const Buffer&) = delete;

  // Immutable storage holding `bytes` bytes of `data`.
  static Buffer make_static(const void* data, size_t bytes, Uploads& uploads);
  // Replaces the contents with `bytes` of `data`, growing the storage (by
  // doubling) when needed. Returns true when the storage was reallocated.
  bool write(const void* data, size_t bytes, Uploads& uploads);

  GLuint id() const { return id_; }
  size_t size() const { return size_; }

 private:
  GLuint id_ = 0;
  size_t capacity_ = 0, size_ = 0;
};

// A 2-D texture array of fixed layer size and format, linearly filtered and
// edge-clamped per layer. It grows by reallocation and a GPU-side copy, so
// layers already filled are never uploaded again.
class TextureArray {
 public:
  TextureArray(GLenum internal_format, GLenum format, GLenum type, size_t texel_bytes);
  ~TextureArray();
  TextureArray(const TextureArray&) = delete;
  TextureArray& operator=(const TextureArray&) = delete;

  // The first call fixes the layer size; later layers must match it.
  bool sized() const { return width_ > 0; }
  void set_layer_size(int width, int height) { width_ = width, height_ = height; }
  int width() const { return width_; }
  int height() const { return height_; }
  int layers() const { return layers_; }
  size_t layer_bytes() const { return static_cast<size_t>(width_) * height_ * texel_bytes_; }
  // Grows to at least `layers` layers, keeping the contents.
  void reserve(int layers);
  void upload(int layer, const void* pixels, Uploads& uploads);
  GLuint id() const { return id_; }

 private:
  GLenum internal_format_, format_, type_;
  size_t texel_bytes_;
  GLuint id_ = 0;
  int width_ = 0, height_ = 0, layers_ = 0;
};

// A buffer texture (samplerBuffer) over a Buffer of RGBA32F texels.
class BufferTexture {
 public:
  BufferTexture();
  ~BufferTexture();
  BufferTexture(const BufferTexture&) = delete;
  BufferTexture& operator=(const BufferTexture&) = delete;
  // Again after the buffer's storage is reallocated.
  void attach(const Buffer& buffer);
  GLuint id() const { return id_; }

 private:
  GLuint id_ = 0;
};

class VertexArray {
 public:
  VertexArray();
  ~VertexArray();
  VertexArray(const VertexArray&) = delete;
  VertexArray& operator=(const VertexArray&) = delete;
  GLuint id() const { return id_; }
  // Integer or float attribute `index` of `count` components at `offset` in binding `binding`.
  void attribute(GLuint index, GLuint binding, GLint count, GLenum type, GLuint offset);

 private:
  GLuint id_ = 0;
};

class Program {
 public:
  // Links a vertex and a fragment shader; `captured` names vertex outputs
  // recorded by transform feedback (tests), interleaved.
  static Result<Program> link(const char* vertex_source, const char* fragment_source,
                              const std::vector<const char*>& captured = {});
  // Compiles and links a compute shader.
  static Result<Program> link_compute(const char* source);
  Program() = default;
  ~Program();
  Program(Program&& o) noexcept;
  Program& operator=(Program&& o) noexcept;
  Program(const Program&) = delete;
  Program& operator=(const Program&) = delete;

  GLuint id() const { return id_; }
  GLint location(const char* name);

 private:
  GLuint id_ = 0;
  std::unordered_map<std::string, GLint> locations_;
};

}  // namespace relief::render::gl
