#pragma once
// `relief render ... --parallel MODE`: one still rendered by every rank of
// an MPI run (libs/parallel), assembled or composited on rank 0, or one
// display image per rank of a wall.
#include "args.h"

namespace relief::cli {

// Returns the process's exit code; errors are one line on stderr (from rank 0
// for errors every rank meets alike, from the failing rank otherwise).
int render_parallel(const Args& args);

}  // namespace relief::cli
