#include <cstdio>

#include "args.h"
#include "commands.h"
#include "relief/tiles/upgrade.h"

namespace relief::cli {

namespace {
constexpr const char* kUpgradeHelp = R"(usage: relief upgrade STORE [--threads N] [-q]

Brings a local store written by an older relief up to the current store
format. From format 1: computes every tile's geometric error (elevation
stores; 0 for imagery and SAR) and rewrites the level indexes and the
manifest. Nothing is written until every error is computed; an interrupted
upgrade is finished by running the command again. A store already in the
current format is left alone.
)";
}  // namespace

int run_upgrade(const std::vector<std::string>& argv) {
  if (wants_help(argv)) return print_help(kUpgradeHelp);
  auto args = Args::parse(argv, {{"--threads"}, {"--quiet", "-q", false}}, "upgrade");
  if (!args) return report_error(args.error().message);
  if (args->positional().size() != 1) return report_error("upgrade: expected exactly one STORE");
  auto threads = args->get_int("--threads", 1, 1024);
  if (!threads) return report_error(threads.error().message);
  ThreadExecutor executor(threads->value_or(0));
  auto progress =
      args->has("--quiet") ? std::make_unique<NullProgress>() : make_progress_for_stderr();
  const std::string& store = args->positional()[0];
  auto report = tiles::upgrade_store(store, executor, *progress);
  if (!report) return report_error(report.error().message);
  if (report->from_version == report->to_version) {
    std::printf("%s: already at store format version %d, nothing to do\n", store.c_str(),
                report->to_version);
    return 0;
  }
  std::printf("%s: upgraded from store format version %d to %d (%llu tiles)\n", store.c_str(),
              report->from_version, report->to_version,
              static_cast<unsigned long long>(report->tiles));
  return 0;
}

}  // namespace relief::cli
