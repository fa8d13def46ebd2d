#include <cstdio>
#include <limits>

#include <fmt/format.h>

#include "args.h"
#include "commands.h"
#include "detector_options.h"
#include "output_safety.h"
#include "relief/ingest/detect_targets.h"

namespace relief::cli {

namespace {
constexpr const char* kDetectHelp =
    R"(usage: relief detect INPUT -o TARGETS.geojson [options]

Finds point-target responses (a bright peak with side lobes along two axes) in
a SAR amplitude raster GDAL reads, and writes them as GeoJSON points in WGS84
with the two side-lobe directions and a rough peak side-lobe ratio (PSLR).
A sample is a target centre when its amplitude is at least --level times the
image's maximum, it is the maximum of its 7 x 7 neighbourhood, and the mean
amplitudes along its two strongest line masks (12 directions, 0-165 degrees,
at least 45 degrees apart) reach --sensitivity times the 7 x 7 mean.

options:
  -o, --output FILE      GeoJSON to write (atomically)
  --level F              amplitude floor as a fraction of the maximum, (0, 1] (default 0.15)
  --sensitivity T        t > 0; higher finds fewer targets (default 1.5)
  --analysis FILE        analyse one target: cross-sections along both axes,
                         PSLR and -3 dB widths as JSON
  --plot FILE.png        the cross-sections of the analysed target as a plot
                         (red: first axis, blue: second, grey: PSLR level, 10 dB grid)
  --analyse X,Y          the target analysed: the detection nearest pixel X,Y
                         (default: the strongest)
  --half-length N        cross-section samples either side of the peak (default 32)
  --threads N            worker threads (default: one per core)
  -q, --quiet            no progress bar
)";
}  // namespace

int run_detect(const std::vector<std::string>& argv) {
  if (wants_help(argv)) return print_help(kDetectHelp);
  auto args = Args::parse(argv,
                          {{"--output", "-o"},
                           {"--level"},
                           {"--sensitivity"},
                           {"--analysis"},
                           {"--plot"},
                           {"--analyse"},
                           {"--half-length"},
                           {"--threads"},
                           {"--quiet", "-q", false}},
                          "detect");
  if (!args) return report_error(args.error().message);
  if (args->positional().size() != 1) return report_error("detect: expected exactly one INPUT");
  if (!args->get("--output")) return report_error("detect: -o TARGETS.geojson is required");
  ingest::DetectOptions o;
  o.input = args->positional()[0];
  o.geojson = *args->get("--output");
  auto detector = parse_detector_params(*args, "--level", "--sensitivity");
  if (!detector) return report_error(detector.error().message);
  o.detector = *detector;
  if (auto a = args->get("--analysis")) o.analysis_json = *a;
  if (auto p = args->get("--plot")) o.analysis_png = *p;
  if (auto at = args->get("--analyse")) {
    auto xy =
        parse_int_pair("--analyse", *at, ',', 0, std::numeric_limits<int>::max(), "X,Y in pixels");
    if (!xy) return report_error(xy.error().message);
    o.analyse_at = *xy;
  }
  std::vector<Output> outputs = {{"-o", o.geojson.string()}};
  if (!o.analysis_json.empty()) outputs.push_back({"--analysis", o.analysis_json.string()});
  if (!o.analysis_png.empty()) outputs.push_back({"--plot", o.analysis_png.string()});
  if (auto safe = check_outputs_spare_inputs(outputs, {o.input}); !safe) {
    return report_error(safe.error().message);
  }
  auto half = args->get_int("--half-length", 4, 1000);
  if (!half) return report_error(half.error().message);
  if (*half) o.half_length = **half;
  auto threads = args->get_int("--threads", 1, 1024);
  if (!threads) return report_error(threads.error().message);
  ThreadExecutor executor(threads->value_or(0));
  auto progress =
      args->has("--quiet") ? std::make_unique<NullProgress>() : make_progress_for_stderr();
  auto report = ingest::detect_targets(o, executor, *progress);
  if (!report) return report_error(report.error().message);
  std::printf("wrote %s: %zu targets (maximum amplitude %g)\n", o.geojson.c_str(),
              report->detections, report->max_amplitude);
  if (report->analysis) {
    const auto& t = *report->analysis;
    std::printf("analysed target at %lld,%lld: PSLR %.2f dB, -3 dB widths %.2f / %.2f samples\n",
                static_cast<long long>(t.x), static_cast<long long>(t.y), t.pslr_db,
                t.axes[0].width_3db, t.axes[1].width_3db);
  }
  return 0;
}

}  // namespace relief::cli
