#pragma once
// The wavelet soft thresholding (libs/process wavelet.cpp) on the GPU: one
// pass for ln A, two per à trous level (rows, then columns), one for the
// thresholded reconstruction. The planes between passes are doubles, stored
// as two 32-bit halves in RG32UI (row sums and weights in RGBA32UI), so the
// sums equal the CPU's.
#include <map>
#include <string>
#include <vector>

#include "gl_program.h"
#include "relief/base/result.h"
#include "relief/process/operators.h"

namespace relief::gpuprocess {

class WaveletPasses {
 public:
  // Reads `in` (R32F) and writes the step's output texels of `out`: the
  // input's valid region starts `origin` texels in and is width x height;
  // the output region is the wavelet margin smaller on every side.
  Status run(const process::Params& params, const GlTexture& in, const GlTexture& out, int origin,
             int width, int height);
  ~WaveletPasses();

 private:
  Result<GLuint> program(const std::string& name);
  void ensure_planes(int width, int height, size_t levels);

  std::map<std::string, GlProgram> programs_;
  std::vector<GLuint> planes_;  // c_0 .. c_J, RG32UI
  GLuint rows_ = 0;             // row sums and weights, RGBA32UI
  int width_ = 0, height_ = 0;
};

}  // namespace relief::gpuprocess
