#include <cmath>
#include <cstdio>
#include <filesystem>

#include <fmt/format.h>

#include "allocator.h"
#include "args.h"
#include "commands.h"
#include "output_safety.h"
#include "relief/base/units.h"
#include "relief/ingest/process_raster.h"
#include "relief/pipeline/process_store.h"
#include "relief/process/operators.h"

namespace relief::cli {

namespace {
constexpr const char* kProcessHelp =
    R"(usage: relief process INPUT -o OUT.tif --op NAME [--param key=value]... [options]
       relief process STORE -o STORE2 --op NAME [--param key=value]... [options]
       relief process --list

Runs a raster operator over one band of a raster GDAL reads, out of core and on
all cores, and writes a tiled Float32 GeoTIFF with the input's georeferencing.
Nodata (the band's nodata value, or NaN) is left out of every window and kept.

Given a store (a directory with manifest.json), processes every pyramid level
into a new store: tiles agree with each other and with the whole level;
window radii are for the finest level and shrink with coarser levels so masks
keep their size on the ground; global statistics come from the manifest.
Operators for SAR refuse elevation and imagery stores.

options:
  -o, --output PATH    GeoTIFF or store directory to write (atomically; a store must not exist)
  --op NAME            operator (see --list)
  --param key=value    operator parameter; repeat for several
  --list               list every operator with its parameters, ranges and defaults
  --compress NAME      output compression: none (default, as GDAL and OTB), deflate, zstd
  --memory SIZE        memory budget (default 1GiB)
  --threads N          worker threads (default: one per core)
  -q, --quiet          no progress bar
)";

int print_catalogue() {
  for (const auto& op : process::operator_catalogue()) {
    std::printf("%-20s %s (input: %s)\n", op.name.c_str(), op.summary.c_str(), op.input.c_str());
    for (const auto& p : op.params) {
      const std::string def =
          std::isnan(p.default_value) ? "auto" : fmt::format("{:g}", p.default_value);
      std::printf("    %-10s %s in [%g, %g], default %s: %s\n", p.name.c_str(),
                  p.integer ? "integer" : "number", p.min, p.max, def.c_str(), p.meaning.c_str());
    }
  }
  return 0;
}
}  // namespace

int run_process(const std::vector<std::string>& argv) {
  if (wants_help(argv)) return print_help(kProcessHelp);
  // --param may repeat: collect those first, parse the rest normally.
  std::vector<std::string> rest, params;
  for (size_t i = 0; i < argv.size(); ++i) {
    if (argv[i] == "--param") {
      if (i + 1 == argv.size()) return report_error("process: option --param needs a value");
      params.push_back(argv[++i]);
    } else if (argv[i].starts_with("--param=")) {
      params.push_back(argv[i].substr(8));
    } else {
      rest.push_back(argv[i]);
    }
  }
  auto args = Args::parse(rest,
                          {{"--output", "-o"},
                           {"--op"},
                           {"--list", "", false},
                           {"--memory"},
                           {"--compress"},
                           {"--threads"},
                           {"--quiet", "-q", false}},
                          "process");
  if (!args) return report_error(args.error().message);
  if (args->has("--list")) return print_catalogue();
  if (args->positional().size() != 1) return report_error("process: expected exactly one INPUT");
  if (!args->get("--output")) return report_error("process: -o OUT.tif is required");
  if (!args->get("--op")) return report_error("process: --op NAME is required (see --list)");
  ingest::ProcessRasterOptions o;
  o.input = args->positional()[0];
  o.output = *args->get("--output");
  o.op = *args->get("--op");
  o.params = params;
  if (auto c = args->get("--compress")) o.compress = *c;
  if (auto m = args->get("--memory")) {
    auto bytes = parse_memory_budget(*m, uint64_t{16} << 20);
    if (!bytes) return report_error(bytes.error().message);
    o.memory_budget = *bytes;
    fit_allocator_to_budget(*bytes);
  }
  auto threads = args->get_int("--threads", 1, 1024);
  if (!threads) return report_error(threads.error().message);
  ThreadExecutor executor(threads->value_or(0));
  auto progress =
      args->has("--quiet") ? std::make_unique<NullProgress>() : make_progress_for_stderr();
  const bool store_input = std::filesystem::is_directory(o.input);
  const Output output{"-o", o.output.string(), store_input ? OutputKind::Store : OutputKind::File};
  if (auto safe = check_outputs_spare_inputs({output}, {o.input}); !safe) {
    return report_error(safe.error().message);
  }
  if (store_input) {
    pipeline::ProcessStoreOptions so{o.input, o.output, o.op, o.params};
    if (args->get("--memory")) so.memory_budget = o.memory_budget / 2;
    auto r = pipeline::process_store(so, executor, *progress);
    if (!r) return report_error(r.error().message);
    std::printf("wrote %s: %llu tiles on %d levels, %s, %.2f s\n", so.output.c_str(),
                static_cast<unsigned long long>(r->tiles), r->levels, o.op.c_str(), r->seconds);
    return 0;
  }
  auto report = ingest::process_raster(o, executor, *progress);
  if (!report) return report_error(report.error().message);
  std::printf("wrote %s: %d x %d samples, %s, %.2f s (%.1f Msamples/s)\n", o.output.c_str(),
              report->width, report->height, o.op.c_str(), report->seconds,
              report->width * static_cast<double>(report->height) / report->seconds / 1e6);
  return 0;
}

}  // namespace relief::cli
