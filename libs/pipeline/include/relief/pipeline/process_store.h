#pragma once
// `relief process STORE -o STORE2`: runs one operator of the process library
// over every level of a pyramid. Each tile is computed from its 3 x 3
// neighbourhood with the operator's margin, so tiles agree with each other
// and with the whole level processed at once, bit for bit; window sizes are
// scaled per level so masks keep their size in world space (seed 003 §2.3.3);
// global statistics come from the input's manifest.
#include <cstdint>
#include <filesystem>
#include <string>
#include <vector>

#include "relief/base/parallel.h"
#include "relief/base/progress.h"
#include "relief/base/result.h"

namespace relief::pipeline {

struct ProcessStoreOptions {
  std::filesystem::path input, output;  // output must not exist yet
  std::string op;
  std::vector<std::string> params;               // "key=value", for the finest level
  uint64_t memory_budget = uint64_t{512} << 20;  // decoded input tiles held for neighbours
};

struct ProcessStoreReport {
  uint64_t tiles = 0;
  int levels = 0;
  double seconds = 0;
};

Result<ProcessStoreReport> process_store(const ProcessStoreOptions& options, Executor& executor,
                                         Progress& progress);

}  // namespace relief::pipeline
