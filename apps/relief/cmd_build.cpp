#include <cstdio>

#include <fmt/format.h>

#include "allocator.h"
#include "args.h"
#include "commands.h"
#include "relief/base/memory_use.h"
#include "relief/base/units.h"
#include "relief/ingest/build.h"

namespace relief::cli {

namespace {
constexpr const char* kBuildHelp =
    R"(usage: relief build INPUT... -o STORE --kind elevation|imagery|sar [options]

Builds a multi-resolution tile pyramid on the WGS84 geographic quadtree from any
rasters GDAL reads, in any projection. Several inputs are mosaicked into one
dataset. An interrupted build (even kill -9) resumes when run again.

options:
  -o, --output DIR     store directory to create
  --kind KIND          elevation | imagery | sar
  --max-level N        finest level (default: the next level finer than the input)
  --min-level N        coarsest level (default 0)
  --codec NAME         zstd (lossless), lerc (elevation/sar), png, jpeg, webp (imagery)
                       default: zstd, or lerc with --max-error; jpeg for imagery
  --max-error E        LERC: largest absolute error per sample, in data units
  --quality Q          JPEG/WebP quality 1..100 (default 90)
  --tile-size WxH      interior samples per tile, 2^(k+1) x 2^k (default 512x256)
  --border B           overlap border samples on each side (default 9)
  --memory SIZE        memory budget, e.g. 512MiB, 2GiB (default 1GiB)
  --threads N          worker threads (default: one per core)
  --src-crs CRS        CRS for inputs that have none (e.g. EPSG:4326)
  --warp-error PX      reprojection error allowed, in source pixels (default 0.125,
                       as gdalwarp -et; 0 transforms every sample exactly)
  --gdal-warp          resample every input through GDAL's warper, also inputs
                       already in WGS84 lon/lat (same result, slower)
  --fill-voids         elevation: fill nodata holes inside the data (SRTM voids)
                       by pull-push interpolation; nodata reaching an input's
                       edge stays nodata, valid samples are never changed
  --overwrite          replace an existing store
  -q, --quiet          no progress bar
  --timings            print the wall time of each build phase
)";

Result<int> log2_height_from(const std::string& text) {
  const auto [w, h] = RELIEF_TRY(parse_width_height("--tile-size", text, 8192));
  for (int k = 1; k <= 12; ++k) {
    if (h == (1 << k) && w == 2 * h) return k;
  }
  return fail(fmt::format("--tile-size: '{}' must be 2^(k+1) x 2^k, e.g. 512x256", text));
}
}  // namespace

int run_build(const std::vector<std::string>& argv) {
  if (wants_help(argv)) return print_help(kBuildHelp);
  auto args = Args::parse(argv,
                          {{"--output", "-o"},
                           {"--kind"},
                           {"--max-level"},
                           {"--min-level"},
                           {"--codec"},
                           {"--max-error"},
                           {"--quality"},
                           {"--tile-size"},
                           {"--border"},
                           {"--memory"},
                           {"--threads"},
                           {"--src-crs"},
                           {"--warp-error"},
                           {"--overwrite", "", false},
                           {"--quiet", "-q", false},
                           {"--timings", "", false},
                           {"--gdal-warp", "", false},
                           {"--fill-voids", "", false}},
                          "build");
  if (!args) return report_error(args.error().message);
  ingest::BuildOptions o;
  o.inputs = args->positional();
  if (o.inputs.empty())
    return report_error("build: no input files given (see relief build --help)");
  if (!args->get("--output")) return report_error("build: -o STORE is required");
  o.output = *args->get("--output");
  if (!args->get("--kind")) return report_error("build: --kind elevation|imagery|sar is required");
  auto kind = tiles::dataset_kind_from_string(*args->get("--kind"));
  if (!kind) return report_error("--kind: " + kind.error().message);
  o.kind = *kind;

  auto fail_on = [](const Error& e) { return report_error(e.message); };
  auto max_level = args->get_int("--max-level", 0, 24);
  if (!max_level) return fail_on(max_level.error());
  o.max_level = *max_level;
  auto min_level = args->get_int("--min-level", 0, 24);
  if (!min_level) return fail_on(min_level.error());
  o.min_level = *min_level;
  if (auto c = args->get("--codec")) {
    auto codec = tiles::codec_from_string(*c);
    if (!codec) return report_error("--codec: " + codec.error().message);
    o.codec = *codec;
  }
  auto max_error = args->get_double("--max-error");
  if (!max_error) return fail_on(max_error.error());
  if (*max_error) o.max_error = **max_error;
  auto quality = args->get_int("--quality", 1, 100);
  if (!quality) return fail_on(quality.error());
  if (*quality) o.quality = **quality;
  if (auto t = args->get("--tile-size")) {
    auto k = log2_height_from(*t);
    if (!k) return fail_on(k.error());
    o.tile_log2_height = *k;
  }
  auto border = args->get_int("--border", 0, 4096);
  if (!border) return fail_on(border.error());
  if (*border) o.border = **border;
  if (auto m = args->get("--memory")) {
    // The least a build can do with is checked against its thread count later.
    auto bytes = parse_memory_budget(*m, 0);
    if (!bytes) return report_error(bytes.error().message);
    o.memory_budget = *bytes;
    fit_allocator_to_budget(*bytes);
  }
  auto threads = args->get_int("--threads", 1, 1024);
  if (!threads) return fail_on(threads.error());
  if (auto crs = args->get("--src-crs")) o.src_crs = *crs;
  auto warp_error = args->get_double("--warp-error");
  if (!warp_error) return fail_on(warp_error.error());
  if (*warp_error) o.warp_error = **warp_error;
  o.overwrite = args->has("--overwrite");
  o.direct_resampling = !args->has("--gdal-warp");
  o.fill_voids = args->has("--fill-voids");
  o.release_freed_memory = release_freed_memory;

  ThreadExecutor executor(threads->value_or(0));
  auto progress =
      args->has("--quiet") ? std::make_unique<NullProgress>() : make_progress_for_stderr();
  auto report = ingest::build_store(o, executor, *progress);
  if (!report) return report_error(report.error().message);
  const auto& m = report->manifest;
  std::printf("built %s: %s, levels %d..%d, %llu tiles written (%llu resumed) in %.1f s\n",
              o.output.c_str(), std::string(tiles::to_string(m.kind)).c_str(), m.min_level,
              m.max_level, static_cast<unsigned long long>(report->tiles_written),
              static_cast<unsigned long long>(report->tiles_resumed), report->seconds);
  if (report->voids_filled) {
    std::printf("filled %llu void samples in the inputs\n",
                static_cast<unsigned long long>(report->voids_filled));
  }
  if (args->has("--timings")) {
    for (const auto& [phase, seconds] : report->phase_seconds) {
      std::printf("  %-16s %8.3f s\n", phase.c_str(), seconds);
    }
  }
  return 0;
}

}  // namespace relief::cli
