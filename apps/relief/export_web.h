#pragma once
// `relief export --format quantized-mesh|terrain-rgb|terrarium|xyz`: web
// tiles written for any static host (docs/web.md).
#include "args.h"
#include "relief/pipeline/processed_elevation.h"

namespace relief::cli {

// Runs the export of `args` (already parsed by run_export) in `format`.
// `elevation`: the --elevation-op chain, applied (with --elevation layers
// fused) to an elevation store as relief render draws it.
int run_export_web(const Args& args, const std::string& format,
                   pipeline::ElevationProcessing elevation);

}  // namespace relief::cli
