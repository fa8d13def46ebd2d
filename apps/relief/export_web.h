#pragma once
// `relief export --format quantized-mesh|terrain-rgb|terrarium|xyz`: web
// tiles written for any static host (docs/web.md).
#include "args.h"

namespace relief::cli {

// Runs the export of `args` (already parsed by run_export) in `format`.
int run_export_web(const Args& args, const std::string& format);

}  // namespace relief::cli
