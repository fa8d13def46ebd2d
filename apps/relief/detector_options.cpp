#include "detector_options.h"

namespace relief::cli {

Result<process::DetectorParams> parse_detector_params(const Args& args, const std::string& level,
                                                      const std::string& sensitivity) {
  process::DetectorParams p;
  if (auto v = RELIEF_TRY(args.get_double(level))) {
    if (!(*v > 0 && *v <= 1)) return fail(level + ": must be in (0, 1]");
    p.level = *v;
  }
  if (auto v = RELIEF_TRY(args.get_double(sensitivity))) {
    if (!(*v > 0 && *v <= 100)) return fail(sensitivity + ": must be in (0, 100]");
    p.sensitivity = *v;
  }
  return p;
}

}  // namespace relief::cli
