#pragma once
// The GLSL of every operator that runs on the GPU, and the constants each
// step passes to it. Every shader mirrors its libs/process kernel: the same
// formula, evaluated in double precision in the same order (window sums
// column by column, exactly as window_stats.cpp and gauss_stack.cpp add
// them), so results differ from the CPU's only where the GPU's double
// exp/log (shader_math below) round differently.
#include <array>
#include <map>
#include <string>
#include <vector>

#include "relief/gpuprocess/chain.h"
#include "relief/process/dynamic_range.h"

namespace relief::gpuprocess {

// Sizes of the uniform arrays every operator shader declares.
inline constexpr int kConstants = 8;
inline constexpr int kWeights = 361;  // (2 * 9 + 1)^2

// The parts of every one-pass operator shader (shader_prelude.cpp): bindings
// and uniforms, then shader_math(), then main(), which calls the operator's
// `float apply(ivec2 p)`.
std::string shader_frame();
std::string shader_main();

// Operator name -> the GLSL that defines apply() (and what it needs).
using ShaderBodies = std::map<std::string, std::string>;
void add_point_shaders(ShaderBodies& bodies);          // mapping_shaders.cpp
void add_speckle_shaders(ShaderBodies& bodies);        // speckle_shaders.cpp
void add_local_mapping_shaders(ShaderBodies& bodies);  // local_mapping_shaders.cpp

// Whether operator `name` reads its window statistics from a rows pass
// (window_rows_shader(), its output bound to texture unit 1, an RGBA32F
// texture the size of the input, written over the step's output columns and
// r more rows above and below): mean, lee, kuan.
bool uses_window_rows(const std::string& name);
std::string window_rows_shader(int radius);
// Writes out the runs of a window-rows operator's column pass for `radius`.
void with_runs(std::string& source, int radius);

// Double-precision dlog, dlog1p, dlog10, dexp, dpow and the nodata helpers
// (nodata(float), nan_f(), inf_d()), for passes with their own bindings.
std::string shader_math();

// The complete compute shader of operator `name`, or empty when the operator
// has no GPU implementation. With a `radius` >= 0, the radius `r` is that
// constant instead of a uniform (see constant_radius()).
std::string operator_shader(const std::string& name, int radius = -1);

// Whether operator `name` is compiled per radius: its loops then have constant
// bounds, which llvmpipe unrolls (2x less work for the window statistics),
// for a compilation per radius used (a chain uses one per level at most).
bool constant_radius(const std::string& name);
// Makes the `uniform int r;` of a shader the constant `radius`.
void with_radius(std::string& source, int radius);

// The uniforms of one step: `r` (radius, or the largest radius of a Gauss
// stack), `k` (derived constants, computed on the CPU in double as the CPU
// kernel does) and `w` (kernel weights).
struct StepUniforms {
  int r = 0;
  std::array<double, kConstants> k{};
  std::vector<double> w;
};
StepUniforms step_uniforms(const ChainStep& step, const process::GlobalStats& stats);

}  // namespace relief::gpuprocess
