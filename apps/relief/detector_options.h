#pragma once
// The point-target detector's options, shared by `relief detect` (--level,
// --sensitivity) and the draw-time hints of `relief render` and `relief view`
// (--detect-level, --detect-sensitivity): one parser, one set of limits.
#include <string>

#include "args.h"
#include "relief/base/result.h"
#include "relief/process/point_targets.h"

namespace relief::cli {

// The detector's defaults with what `level` (a fraction of the maximum
// amplitude, (0, 1]) and `sensitivity` ((0, 100]) options say; one-line errors.
Result<process::DetectorParams> parse_detector_params(const Args& args, const std::string& level,
                                                      const std::string& sensitivity);

}  // namespace relief::cli
