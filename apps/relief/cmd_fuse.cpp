#include <cstdio>

#include "args.h"
#include "commands.h"
#include "output_safety.h"
#include "relief/pipeline/fuse_stores.h"

namespace relief::cli {

namespace {
constexpr const char* kFuseHelp =
    R"(usage: relief fuse STORE STORE... -o OUT [--weights W,W,...] [--mode blend|first]

Combines stores of the same kind (elevation, imagery or SAR) tile by tile into
a new store on every pyramid level. Nodata in one input leaves the others to
fill in. The per-tile bounds of the result's index combine the inputs' bounds.

options:
  -o, --output DIR     store to write (must not exist; moved into place when complete)
  --weights LIST       one weight > 0 per input, comma-separated (default: all 1)
  --mode NAME          blend: weighted mean of the valid inputs (default);
                       first: the first valid input in the order given (fills voids)
  --allow-upsampling   fuse inputs of very different resolution anyway: the
                       coarser ones are interpolated to the finest level over
                       their whole extent (refused by default when that makes
                       more than 4 times the inputs' tiles)
  --threads N          worker threads (default: one per core)
  -q, --quiet          no progress bar
)";

}  // namespace

int run_fuse(const std::vector<std::string>& argv) {
  if (wants_help(argv)) return print_help(kFuseHelp);
  auto args = Args::parse(argv,
                          {{"--output", "-o"},
                           {"--weights"},
                           {"--mode"},
                           {"--threads"},
                           {"--allow-upsampling", "", false},
                           {"--quiet", "-q", false}},
                          "fuse");
  if (!args) return report_error(args.error().message);
  if (!args->get("--output")) return report_error("fuse: -o OUT is required");
  pipeline::FuseOptions o;
  for (const auto& p : args->positional()) o.inputs.emplace_back(p);
  o.output = *args->get("--output");
  if (auto safe = check_outputs_spare_inputs({{"-o", o.output.string(), OutputKind::Store}},
                                             args->positional());
      !safe) {
    return report_error(safe.error().message);
  }
  if (auto w = args->get("--weights")) {
    auto weights = parse_numbers("--weights", *w);
    if (!weights) return report_error(weights.error().message);
    o.weights = *weights;
  }
  if (auto mode = args->get("--mode")) {
    if (*mode == "blend") {
      o.mode = pipeline::FuseMode::Blend;
    } else if (*mode == "first") {
      o.mode = pipeline::FuseMode::First;
    } else {
      return report_error("--mode: '" + *mode + "' is not blend or first");
    }
  }
  o.allow_upsampling = args->has("--allow-upsampling");
  auto threads = args->get_int("--threads", 1, 1024);
  if (!threads) return report_error(threads.error().message);
  ThreadExecutor executor(threads->value_or(0));
  auto progress =
      args->has("--quiet") ? std::make_unique<NullProgress>() : make_progress_for_stderr();
  auto report = pipeline::fuse_stores(o, executor, *progress);
  if (!report) return report_error(report.error().message);
  std::printf("wrote %s: %llu tiles on %d levels from %zu stores\n", o.output.c_str(),
              static_cast<unsigned long long>(report->tiles), report->levels, o.inputs.size());
  return 0;
}

}  // namespace relief::cli
