#pragma once

// Optional heavy dependencies (MPI, FFmpeg) live in modules of their own that
// a library loads on first use: linked into relief, their shared libraries
// would load with every command (docs/ARCHITECTURE.md, the folder map).

#include <string>

#include "relief/base/result.h"

namespace relief {

// Where a module may be, searched in this order: the path in `env_variable`
// (when set and not empty), beside an installed program (bin/../lib/relief/
// and the file name of `build_path`: relief_loadable_module in
// cmake/relief_install.cmake installs it there), then `build_path`.
struct ModuleLocation {
  std::string what;         // the error's prefix: "parallel", "video"
  std::string description;  // in "the ... is not installed": "MPI module"
  std::string env_variable;
  std::string build_path;
};

// Global makes the module's symbols (and its dependencies') visible to
// libraries loaded later: OpenMPI's own plugins need libmpi's.
enum class SymbolScope { local, global };

// Finds and loads the module (kept for the process's life) and returns the
// address of `symbol` in it; a missing module, a failed load or a missing
// symbol is a one-line error naming the path.
Result<void*> load_module_symbol(const ModuleLocation& location, const std::string& symbol,
                                 SymbolScope scope);

}  // namespace relief
