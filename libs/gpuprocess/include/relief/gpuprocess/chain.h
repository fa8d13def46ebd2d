#pragma once
// An operator chain: operators of the process library applied one after the
// other to a tile with its overlap border, each step consuming its margin of
// the border. The description is shared by the GPU pipeline (gpu_processor.h)
// and by its CPU reference run_chain_cpu(), which calls the process library's
// operators and is what the GPU results are compared against.
#include <string>
#include <vector>

#include "relief/base/parallel.h"
#include "relief/base/result.h"
#include "relief/process/operators.h"
#include "relief/tiles/manifest.h"
#include "relief/tiles/raster.h"

namespace relief::gpuprocess {

struct ChainStep {
  const process::OperatorSpec* op = nullptr;  // from process::find_operator
  process::Params params;                     // every parameter, validated
};

struct OperatorChain {
  std::vector<ChainStep> steps;
};

// One step from an operator name and "key=value" assignments (parameters
// checked against the operator's ranges); unknown operators are errors.
Result<ChainStep> make_step(const std::string& op, const std::vector<std::string>& assignments);

// The chain's parameters for data `factor` (a power of two) times coarser than
// the level they were given for, so masks keep their size on the ground.
OperatorChain scale_chain(const OperatorChain& chain, double factor);

// Samples of border the chain consumes: the sum of its steps' margins.
int chain_margin(const OperatorChain& chain);

// The output keeps a one-sample border (for interpolation at quad edges), so a
// chain fits a tile whose overlap border is `border` when its margin is at
// most border - 1; otherwise a one-line error naming the step that overflows.
Status check_fits(const OperatorChain& chain, int border);

// Global statistics needed (a dynamic-range step) but missing or without a
// dynamic range, or a log mapping with t_max <= t_min: an error.
Status check_stats(const OperatorChain& chain, const process::GlobalStats* stats);

// Whether `chain` may run on the tiles of a store with manifest `m` (named
// `name` in errors): operators need single-band stores, SAR operators a SAR
// store; the chain, with parameters for the store's finest level, must fit its
// border there (coarser levels have smaller masks), and the store's
// statistics must suit the mappings. One-line errors.
Status check_chain_for(const OperatorChain& chain, const tiles::Manifest& m,
                       const std::string& name);

// The CPU reference: `tile` is a Float32 single-band raster whose outer
// `border` samples are overlap; the result is the tile's interior plus a
// one-sample border. `stats` are the input dataset's global statistics (from
// the manifest), given to every step that needs them.
Result<tiles::Raster> run_chain_cpu(const OperatorChain& chain, const tiles::Raster& tile,
                                    int border, const process::GlobalStats* stats,
                                    Executor& executor);

}  // namespace relief::gpuprocess
