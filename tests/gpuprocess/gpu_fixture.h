#pragma once
// What the GPU processing tests share: one headless GL context and processor
// per test binary, the bundled SAR image built into a store, and the
// comparison of a GPU result with the CPU reference.
#include <string>
#include <vector>

#include "relief/gpuprocess/gpu_processor.h"
#include "relief/tiles/store.h"

namespace relief::testing {

gpuprocess::GpuProcessor& gpu();
const tiles::Store& sar_store();
process::GlobalStats sar_stats();

gpuprocess::OperatorChain chain_of(
    const std::vector<std::pair<std::string, std::vector<std::string>>>& steps);

// Largest |gpu - cpu| / |cpu| over the samples (0 where both are 0), or
// infinity when nodata differs or the shapes differ.
double max_relative_error(const tiles::Raster& gpu, const tiles::Raster& cpu);

// Runs `chain` (parameters for the finest level, scaled per level as
// `relief process` does) on the GPU and on the CPU over up to `tiles` tiles
// of each of the finest three levels and expects them equal within
// `tolerance` relative; returns the largest error seen.
double expect_gpu_equals_cpu(const gpuprocess::OperatorChain& chain, double tolerance,
                             int tiles = 2);

}  // namespace relief::testing
