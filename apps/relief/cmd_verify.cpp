#include <cstdio>

#include "args.h"
#include "commands.h"
#include "relief/tiles/verify.h"

namespace relief::cli {

namespace {
constexpr const char* kVerifyHelp = R"(usage: relief verify STORE [--threads N] [-q]

Checks the manifest, every level index and every tile (header, checksum,
payload), and for an elevation store recomputes every tile's geometric error
and compares it with the level index. Prints one line per problem and exits
non-zero if any is found.
)";
}  // namespace

int run_verify(const std::vector<std::string>& argv) {
  if (wants_help(argv)) return print_help(kVerifyHelp);
  auto args = Args::parse(argv, {{"--threads"}, {"--quiet", "-q", false}}, "verify");
  if (!args) return report_error(args.error().message);
  if (args->positional().size() != 1) return report_error("verify: expected exactly one STORE");
  auto threads = args->get_int("--threads", 1, 1024);
  if (!threads) return report_error(threads.error().message);
  ThreadExecutor executor(threads->value_or(0));
  auto progress =
      args->has("--quiet") ? std::make_unique<NullProgress>() : make_progress_for_stderr();
  const auto report = tiles::verify_store(args->positional()[0], executor, *progress);
  for (const auto& p : report.problems) std::fprintf(stderr, "relief: %s\n", p.c_str());
  if (!report.ok()) {
    std::printf("%s: %zu problem(s) in %llu tiles checked\n", args->positional()[0].c_str(),
                report.problems.size(), static_cast<unsigned long long>(report.tiles_checked));
    return 1;
  }
  std::printf("%s: ok, %llu tiles checked\n", args->positional()[0].c_str(),
              static_cast<unsigned long long>(report.tiles_checked));
  return 0;
}

}  // namespace relief::cli
