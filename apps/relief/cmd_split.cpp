#include <cstdio>

#include "args.h"
#include "commands.h"
#include "output_safety.h"
#include "relief/tiles/split.h"

namespace relief::cli {

namespace {
constexpr const char* kSplitHelp = R"(usage: relief split STORE -o DIR --shares N

Spreads a local store over N servers cyclically (seed 000 §3.1): writes
DIR/share-0 ... DIR/share-(N-1), each with the manifest, every level index and
the tiles whose Morton index modulo N is its number, so neighbouring tiles
live on different servers and no server is a hot spot. Files are hard-linked
where the file system allows, else copied. Serve each share with any static
server (nginx, ...) or `relief serve`; read them in share order:

  relief render cyclic:http://a/,http://b/,http://c/ ...

`relief serve STORE --share I/N` serves share I straight from the whole store.

options:
  -o, --output DIR   directory to write (must not exist; moved into place when complete)
  --shares N         number of servers, 2..4096
)";
}  // namespace

int run_split(const std::vector<std::string>& argv) {
  if (wants_help(argv)) return print_help(kSplitHelp);
  auto args = Args::parse(argv, {{"--output", "-o"}, {"--shares"}}, "split");
  if (!args) return report_error(args.error().message);
  if (args->positional().size() != 1) return report_error("split: expected exactly one STORE");
  if (!args->get("--output")) return report_error("split: -o DIR is required");
  auto shares = args->get_int("--shares", 2, 4096);
  if (!shares) return report_error(shares.error().message);
  if (!*shares) return report_error("split: --shares N is required");
  const std::string output = *args->get("--output");
  if (auto safe =
          check_outputs_spare_inputs({{"-o", output, OutputKind::Store}}, args->positional());
      !safe) {
    return report_error(safe.error().message);
  }
  auto report = tiles::split_store(args->positional()[0], output, static_cast<uint32_t>(**shares));
  if (!report) return report_error(report.error().message);
  std::printf("wrote %s: %d shares, %llu tiles (%llu hard-linked)\n", output.c_str(), **shares,
              static_cast<unsigned long long>(report->tiles),
              static_cast<unsigned long long>(report->linked));
  return 0;
}

}  // namespace relief::cli
