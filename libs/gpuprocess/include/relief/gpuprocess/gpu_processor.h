#pragma once
// The GPU operator pipeline (seed 003 §1.3.3): a tile with its overlap border
// is uploaded as an R32F texture, every step of an operator chain runs as
// compute-shader passes between two ping-pong R32F textures, and the tile's
// interior with a one-sample border is read back. Results equal the CPU
// operators of libs/process within the tolerances of docs/gpu-processing.md.
//
// Thread safety: a processor belongs to the thread whose GL 4.5 core context
// was current at create(); it is used on that thread, with that context
// current, only.
#include <cstdint>
#include <memory>
#include <string>

#include "relief/base/result.h"
#include "relief/gpuprocess/chain.h"
#include "relief/process/dynamic_range.h"
#include "relief/tiles/raster.h"

namespace relief::gpuprocess {

// Whether operator `name` has a GPU implementation.
bool runs_on_gpu(const std::string& name);

// Where GpuProcessor::run_on_gpu() leaves its result: texels [offset, offset +
// width) x [offset, offset + height) of the R32F texture `texture` (a GL
// name) are the tile's interior plus a one-sample border.
struct GpuTile {
  uint32_t texture = 0;
  int offset = 0, width = 0, height = 0;
};

class GpuProcessor {
 public:
  // Needs a current GL 4.5 core context (render::GlContext::create_headless(),
  // or a window's).
  static Result<std::unique_ptr<GpuProcessor>> create();
  ~GpuProcessor();
  GpuProcessor(const GpuProcessor&) = delete;
  GpuProcessor& operator=(const GpuProcessor&) = delete;

  // As run_chain_cpu(): `tile` is Float32, one band, with `border` overlap
  // samples on every side; the result is its interior plus a one-sample
  // border. Fails on a chain that does not fit the border, missing
  // statistics, or an operator without a GPU implementation.
  Result<tiles::Raster> run(const OperatorChain& chain, const tiles::Raster& tile, int border,
                            const process::GlobalStats* stats);

  // The same without reading the result back (draw-time processing: the
  // result is composited on the GPU). The texture is the processor's and
  // holds the result until the next call of run() or run_on_gpu().
  Result<GpuTile> run_on_gpu(const OperatorChain& chain, const tiles::Raster& tile, int border,
                             const process::GlobalStats* stats);

 private:
  struct Impl;
  explicit GpuProcessor(std::unique_ptr<Impl> impl);
  std::unique_ptr<Impl> impl_;
};

}  // namespace relief::gpuprocess
