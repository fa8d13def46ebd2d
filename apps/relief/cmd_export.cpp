#include <algorithm>
#include <cstdio>
#include <sstream>

#include <fmt/format.h>

#include "allocator.h"
#include "args.h"
#include "commands.h"
#include "elevation_options.h"
#include "export_web.h"
#include "output_safety.h"
#include "relief/ingest/export.h"
#include "relief/tiles/store.h"

namespace relief::cli {

namespace {
constexpr const char* kExportHelp =
    R"(usage: relief export STORE --level L [--bbox W,S,E,N] [--memory SIZE] -o OUT.tif
       relief export STORE --format quantized-mesh [--max-level M] [--bbox W,S,E,N]
                     [--max-error METRES] [--threads N] -o DIR
       relief export STORE --format terrain-rgb|terrarium|xyz|xyz-webp [--tile-size 256|512]
                     [--max-zoom Z] [--bbox W,S,E,N] [--threads N] -o DIR

Reassembles tile interiors of one level into a GeoTIFF (EPSG:4326, the store's
sample grid; NaN or alpha marks nodata). The box is snapped outwards to samples.
--memory bounds the whole process (default 256MiB, at least 96MiB), whatever
the size of the output.

--format quantized-mesh writes Cesium terrain for a static web host:
DIR/layer.json and DIR/{z}/{x}/{y}.terrain (gzip-compressed: serve them with
"Content-Encoding: gzip", docs/web.md), every level up to M (default: the
store's finest). Each mesh keeps the level's lattice within CesiumJS's error
for the level (an eighth of it at the finest level) unless --max-error says
otherwise.

--format terrain-rgb and terrarium write the heights of an elevation store as
Web Mercator XYZ PNG tiles for MapLibre's raster-dem sources (encoding "mapbox"
or "terrarium"), --format xyz the colours of an imagery store:
DIR/tiles.json and DIR/{z}/{x}/{y}.png, 256 pixels a side (or --tile-size
512), zooms 0 to Z (default: the first zoom whose pixels all read the store's
finest level; larger zooms are upsampled from it). Nodata is 0 m in a DEM,
transparent in imagery. --format xyz-webp writes the imagery as lossy WebP
(quality 85, lossless alpha; {z}/{x}/{y}.webp), a fraction of PNG's bytes.

The web formats of an elevation store take its elevation as relief render
draws it: --elevation STORE2 (repeatable) [--fuse first|mean] [--weights
W1,W2,..] fuse layers, --elevation-op OP [--elevation-param K=V] apply a
chain (relief render --help).

Web exports are written beside DIR and moved into place when complete; an
earlier web export at DIR is replaced, anything else there is refused.
)";

Result<geo::GeoBox> parse_bbox(const std::string& text) {
  double v[4];
  std::istringstream in(text);
  char comma = 0;
  for (int i = 0; i < 4; ++i) {
    if (!(in >> v[i]) || (i < 3 && (!(in >> comma) || comma != ','))) {
      return fail(fmt::format("--bbox: '{}' is not W,S,E,N", text));
    }
  }
  if (in >> comma) return fail(fmt::format("--bbox: '{}' is not W,S,E,N", text));
  return geo::GeoBox{v[0], v[1], v[2], v[3]};
}
}  // namespace

int run_export(const std::vector<std::string>& argv) {
  if (wants_help(argv)) return print_help(kExportHelp);
  // Repeatable and ordered: taken out before the other options are parsed.
  std::vector<std::string> rest = argv;
  auto elevation = take_elevation_processing(rest);
  if (!elevation) return report_error(elevation.error().message);
  auto args = Args::parse(rest,
                          {{"--level"},
                           {"--bbox"},
                           {"--memory"},
                           {"--output", "-o"},
                           {"--quiet", "-q", false},
                           {"--format"},
                           {"--max-level"},
                           {"--max-error"},
                           {"--threads"},
                           {"--tile-size"},
                           {"--max-zoom"},
                           {"--elevation"},
                           {"--fuse"},
                           {"--weights"}},
                          "export");
  if (!args) return report_error(args.error().message);
  if (args->positional().size() != 1) return report_error("export: expected exactly one STORE");
  if (auto format = args->get("--format"); format && *format != "geotiff") {
    return run_export_web(*args, *format, std::move(*elevation));
  }
  if (!elevation->empty()) {
    return report_error("export: --elevation-op applies to the web formats only");
  }
  for (const char* web_only : {"--max-level", "--max-error", "--threads", "--tile-size",
                               "--max-zoom", "--elevation", "--fuse", "--weights"}) {
    if (args->has(web_only)) {
      return report_error(fmt::format(
          "export: {} applies to the web formats only (quantized-mesh, terrain-rgb, terrarium, "
          "xyz, xyz-webp)",
          web_only));
    }
  }
  ingest::ExportOptions o;
  o.store = args->positional()[0];
  auto level = args->get_int("--level", 0, 30);
  if (!level) return report_error(level.error().message);
  if (!*level) return report_error("export: --level L is required");
  o.level = **level;
  if (auto b = args->get("--bbox")) {
    auto box = parse_bbox(*b);
    if (!box) return report_error(box.error().message);
    o.bbox = *box;
  } else if (auto store = tiles::Store::open(o.store)) {
    // The extent may reach half a sample past the antimeridian (a grid of
    // 0..360 wrapped): the export covers its part of the globe.
    const geo::GeoBox& e = store->manifest().extent;
    o.bbox = geo::GeoBox{std::max(e.west, -180.0), std::max(e.south, -90.0),
                         std::min(e.east, 180.0), std::min(e.north, 90.0)};
  }
  if (auto m = args->get("--memory")) {
    auto bytes = parse_memory_budget(*m, ingest::kExportMinimumBudget);
    if (!bytes) return report_error(bytes.error().message);
    o.memory_budget = *bytes;
    fit_allocator_to_budget(*bytes);
  }
  if (!args->get("--output")) return report_error("export: -o OUT.tif is required");
  o.output = *args->get("--output");
  if (auto safe = check_outputs_spare_inputs({{"-o", o.output.string()}}, {o.store.string()});
      !safe) {
    return report_error(safe.error().message);
  }
  auto progress =
      args->has("--quiet") ? std::make_unique<NullProgress>() : make_progress_for_stderr();
  auto report = ingest::export_geotiff(o, *progress);
  if (!report) {
    // Without --bbox the box is the store's extent: say so, not "--bbox".
    const std::string_view option = "--bbox: ";
    std::string message = report.error().message;
    if (!args->get("--bbox") && message.starts_with(option)) {
      message = fmt::format("{}: the store's extent, exported without --bbox, {}", o.store.string(),
                            message.substr(option.size()));
    }
    return report_error(message);
  }
  std::printf("wrote %s: %d x %d samples from %d tiles\n", o.output.c_str(), report->width,
              report->height, report->tiles_read);
  return 0;
}

}  // namespace relief::cli
