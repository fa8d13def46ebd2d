#include "gl_backend.h"

#include <algorithm>
#include <utility>

namespace relief::render::gl {

Buffer::~Buffer() {
  if (id_) glDeleteBuffers(1, &id_);
}

Buffer::Buffer(Buffer&& o) noexcept
    : id_(std::exchange(o.id_, 0)), capacity_(o.capacity_), size_(o.size_) {}

Buffer& Buffer::operator=(Buffer&& o) noexcept {
  std::swap(id_, o.id_);
  std::swap(capacity_, o.capacity_);
  std::swap(size_, o.size_);
  return *this;
}

Buffer Buffer::make_static(const void* data, size_t bytes, Uploads& uploads) {
  Buffer b;
  glCreateBuffers(1, &b.id_);
  glNamedBufferStorage(b.id_, static_cast<GLsizeiptr>(std::max<size_t>(bytes, 4)), data, 0);
  b.capacity_ = b.size_ = bytes;
  uploads.geometry += bytes;
  return b;
}

bool Buffer::write(const void* data, size_t bytes, Uploads& uploads) {
  bool grown = false;
  if (bytes > capacity_ || !id_) {
    if (id_) glDeleteBuffers(1, &id_);
    capacity_ = std::max({bytes, capacity_ * 2, size_t{256}});
    glCreateBuffers(1, &id_);
    glNamedBufferStorage(id_, static_cast<GLsizeiptr>(capacity_), nullptr, GL_DYNAMIC_STORAGE_BIT);
    grown = true;
  }
  if (bytes) glNamedBufferSubData(id_, 0, static_cast<GLsizeiptr>(bytes), data);
  size_ = bytes;
  uploads.geometry += bytes;
  return grown;
}

TextureArray::TextureArray(GLenum internal_format, GLenum format, GLenum type, size_t texel_bytes)
    : internal_format_(internal_format), format_(format), type_(type), texel_bytes_(texel_bytes) {}

TextureArray::~TextureArray() {
  if (id_) glDeleteTextures(1, &id_);
}

void TextureArray::reserve(int layers) {
  if (layers <= layers_) return;
  GLuint t = 0;
  glCreateTextures(GL_TEXTURE_2D_ARRAY, 1, &t);
  glTextureStorage3D(t, 1, internal_format_, width_, height_, layers);
  glTextureParameteri(t, GL_TEXTURE_MIN_FILTER, GL_LINEAR);
  glTextureParameteri(t, GL_TEXTURE_MAG_FILTER, GL_LINEAR);
  glTextureParameteri(t, GL_TEXTURE_WRAP_S, GL_CLAMP_TO_EDGE);
  glTextureParameteri(t, GL_TEXTURE_WRAP_T, GL_CLAMP_TO_EDGE);
  if (id_) {  // GPU to GPU: nothing crosses the bus again
    glCopyImageSubData(id_, GL_TEXTURE_2D_ARRAY, 0, 0, 0, 0, t, GL_TEXTURE_2D_ARRAY, 0, 0, 0, 0,
                       width_, height_, layers_);
    glDeleteTextures(1, &id_);
  }
  id_ = t;
  layers_ = layers;
}

void TextureArray::upload(int layer, const void* pixels, Uploads& uploads) {
  glPixelStorei(GL_UNPACK_ALIGNMENT, 1);
  glTextureSubImage3D(id_, 0, 0, 0, layer, width_, height_, 1, format_, type_, pixels);
  uploads.textures += layer_bytes();
}

BufferTexture::BufferTexture() {
  glCreateTextures(GL_TEXTURE_BUFFER, 1, &id_);
}

BufferTexture::~BufferTexture() {
  glDeleteTextures(1, &id_);
}

void BufferTexture::attach(const Buffer& buffer) {
  glTextureBuffer(id_, GL_RGBA32F, buffer.id());
}

VertexArray::VertexArray() {
  glCreateVertexArrays(1, &id_);
}

VertexArray::~VertexArray() {
  glDeleteVertexArrays(1, &id_);
}

void VertexArray::attribute(GLuint index, GLuint binding, GLint count, GLenum type, GLuint offset) {
  glEnableVertexArrayAttrib(id_, index);
  if (type == GL_UNSIGNED_INT || type == GL_INT) {
    glVertexArrayAttribIFormat(id_, index, count, type, offset);
  } else {
    glVertexArrayAttribFormat(id_, index, count, type, GL_FALSE, offset);
  }
  glVertexArrayAttribBinding(id_, index, binding);
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

Result<GLuint> compile(GLenum type, const char* source) {
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
}
}  // namespace

Result<Program> Program::link_compute(const char* source) {
  const GLuint cs = RELIEF_TRY(compile(GL_COMPUTE_SHADER, source));
  Program p;
  p.id_ = glCreateProgram();
  glAttachShader(p.id_, cs);
  glLinkProgram(p.id_);
  glDeleteShader(cs);
  GLint ok = 0;
  glGetProgramiv(p.id_, GL_LINK_STATUS, &ok);
  if (!ok) return fail("GLSL link: " + info_log(p.id_, true));
  return p;
}

Result<Program> Program::link(const char* vertex_source, const char* fragment_source,
                              const std::vector<const char*>& captured) {
  const GLuint vs = RELIEF_TRY(compile(GL_VERTEX_SHADER, vertex_source));
  auto fs = compile(GL_FRAGMENT_SHADER, fragment_source);
  if (!fs) {
    glDeleteShader(vs);
    return fail(fs.error().message);
  }
  Program p;
  p.id_ = glCreateProgram();
  glAttachShader(p.id_, vs);
  glAttachShader(p.id_, *fs);
  if (!captured.empty()) {
    glTransformFeedbackVaryings(p.id_, static_cast<GLsizei>(captured.size()), captured.data(),
                                GL_INTERLEAVED_ATTRIBS);
  }
  glLinkProgram(p.id_);
  glDeleteShader(vs);
  glDeleteShader(*fs);
  GLint ok = 0;
  glGetProgramiv(p.id_, GL_LINK_STATUS, &ok);
  if (!ok) return fail("GLSL link: " + info_log(p.id_, true));
  return p;
}

Program::~Program() {
  if (id_) glDeleteProgram(id_);
}

Program::Program(Program&& o) noexcept
    : id_(std::exchange(o.id_, 0)), locations_(std::move(o.locations_)) {}

Program& Program::operator=(Program&& o) noexcept {
  std::swap(id_, o.id_);
  std::swap(locations_, o.locations_);
  return *this;
}

GLint Program::location(const char* name) {
  auto it = locations_.find(name);
  if (it == locations_.end()) it = locations_.emplace(name, glGetUniformLocation(id_, name)).first;
  return it->second;
}

}  // namespace relief::render::gl
