#include "gl_program.h"

#include <vector>

#include <fmt/format.h>

namespace relief::gpuprocess {

GlProgram::~GlProgram() {
  if (id_) glDeleteProgram(id_);
}

Result<GlProgram> compile_compute(const std::string& name, const std::string& source) {
  const GLuint shader = glCreateShader(GL_COMPUTE_SHADER);
  const char* text = source.c_str();
  glShaderSource(shader, 1, &text, nullptr);
  glCompileShader(shader);
  GLint ok = 0;
  glGetShaderiv(shader, GL_COMPILE_STATUS, &ok);
  if (!ok) {
    std::vector<char> log(4096);
    glGetShaderInfoLog(shader, static_cast<GLsizei>(log.size()), nullptr, log.data());
    glDeleteShader(shader);
    return fail(fmt::format("{}: compute shader does not compile: {}", name, log.data()));
  }
  GlProgram program(glCreateProgram());
  glAttachShader(program.id(), shader);
  glLinkProgram(program.id());
  glDeleteShader(shader);  // freed with the program
  glGetProgramiv(program.id(), GL_LINK_STATUS, &ok);
  if (!ok) {
    std::vector<char> log(4096);
    glGetProgramInfoLog(program.id(), static_cast<GLsizei>(log.size()), nullptr, log.data());
    return fail(fmt::format("{}: compute program does not link: {}", name, log.data()));
  }
  return program;
}

GlTexture::GlTexture(int width, int height, GLenum internal_format)
    : width_(width), height_(height) {
  glCreateTextures(GL_TEXTURE_2D, 1, &id_);
  glTextureStorage2D(id_, 1, internal_format, width, height);
  glTextureParameteri(id_, GL_TEXTURE_MIN_FILTER, GL_NEAREST);
  glTextureParameteri(id_, GL_TEXTURE_MAG_FILTER, GL_NEAREST);
}

GlTexture::~GlTexture() {
  if (id_) glDeleteTextures(1, &id_);
}

}  // namespace relief::gpuprocess
