#pragma once
// Edge-mark refinement's split criterion for every diamond of every quad in
// a GL 4.5 compute shader, in double precision (seed 003 §3.4.1: exact
// screen positions on a global scale need it; §3.5: one GPU thread per edge
// mark). What lod::refine() asks of a lod::CriterionEvaluator: per diamond,
// under the threshold, over it, or within a millionth of it (refine() then
// evaluates that one itself), so the mesh is the CPU's bit for bit.
//
// Used on the thread that owns the GL context, as the renderer.
#include <cstdint>
#include <memory>

#include "relief/base/result.h"
#include "relief/lod/criterion_evaluator.h"

namespace relief::render {

class GlRefineCriteria final : public lod::CriterionEvaluator {
 public:
  // Compiles the shader in the calling thread's current GL context. The
  // tiles' diamond errors stay on the GPU between frames within
  // `budget_bytes` (a frame's own may exceed it).
  static Result<std::unique_ptr<GlRefineCriteria>> create(uint64_t budget_bytes = uint64_t{256}
                                                                                  << 20);
  ~GlRefineCriteria() override;

  Status evaluate(const lod::CriterionFrame& frame, std::span<const lod::CriterionQuad> quads,
                  std::vector<std::vector<uint8_t>>& classes) override;

  // Bytes sent to the GPU and read back since creation.
  uint64_t bytes_uploaded() const;
  uint64_t bytes_read() const;
  uint64_t resident_bytes() const;  // diamond errors kept on the GPU

 private:
  struct Impl;
  explicit GlRefineCriteria(std::unique_ptr<Impl> impl);
  std::unique_ptr<Impl> impl_;
};

}  // namespace relief::render
