#pragma once
// The one check every command that writes runs before writing anything: no
// output may replace, or land inside, what the command reads. Paths are
// compared as the file system sees them (symlinks resolved, hard links by
// device and inode), so `-o ./link-to-input.tif` is caught like `-o input.tif`.
#include <string>
#include <vector>

#include "relief/base/result.h"

namespace relief::cli {

enum class OutputKind {
  File,       // one file, written atomically (GeoTIFF, PNG, JSON)
  Store,      // a new store directory
  Directory,  // an existing or new directory that receives files (frames, a cache)
};

struct Output {
  std::string option;  // as the user wrote it: "-o", "--plot", ...; named in errors
  std::string path;
  OutputKind kind = OutputKind::File;
};

// Fails, with a one-line error naming the option, when an output
// - is an input (same resolved path, or the same file through a hard link),
// - lies inside an input store (writing there breaks it),
// - is a store that would contain an input,
// - is an existing device, FIFO, socket or directory where a file is written,
// - is the same path as another output.
// Remote inputs (URLs) and inputs that do not exist are left to the command.
Status check_outputs_spare_inputs(const std::vector<Output>& outputs,
                                  const std::vector<std::string>& inputs);

}  // namespace relief::cli
