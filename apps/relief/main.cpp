// relief: the command line. Exceptions stop here; libraries return errors as values.
#include <csignal>
#include <cstdio>
#include <exception>
#include <string>
#include <vector>

#include "allocator.h"
#include "commands.h"

namespace {

constexpr const char* kUsage = R"(relief: explore very large terrain and remote-sensing rasters

usage: relief <command> [options]

commands:
  build    turn rasters (GeoTIFF, SRTM .hgt, VRT, DTED, ...) into a tile pyramid store
  info     describe a store: manifest, tiles and bytes per level, compression
  verify   check every tile header and checksum of a store
  upgrade  bring a store written by an older relief up to the current format
  export   one level of a store as a GeoTIFF, or Cesium terrain tiles
  process  run an operator (speckle filter, dynamic-range reduction, ...) over a GeoTIFF or a store
  fuse     combine stores of one kind tile by tile (weighted blend or void filling)
  detect   find point targets in a SAR image: GeoJSON, analysis JSON and plot
  render   render a still of an elevation store (headless OpenGL), optionally with imagery
  serve    serve a store read-only over HTTP
  split    spread a store over several servers (cyclic shares)
  view     fly over a store in a window (GLFW), record and play back camera paths

Run 'relief <command> --help' for the options of a command.
)";

}  // namespace

namespace relief::cli {

int report_error(const std::string& message) {
  std::fprintf(stderr, "relief: %s\n", message.c_str());
  return 1;
}

bool wants_help(const std::vector<std::string>& args) {
  for (const auto& a : args) {
    if (a == "--help" || a == "-h") return true;
  }
  return false;
}

int print_help(const char* text) {
  std::fputs(text, stdout);
  return 0;
}

}  // namespace relief::cli

int main(int argc, char** argv) {
  // A write past a file-size limit must fail with EFBIG, not kill the process.
  std::signal(SIGXFSZ, SIG_IGN);
  std::vector<std::string> args(argv + 1, argv + argc);
  if (args.empty() || args[0] == "--help" || args[0] == "-h" || args[0] == "help") {
    std::fputs(kUsage, args.empty() ? stderr : stdout);
    return args.empty() ? 2 : 0;
  }
  const std::string command = args[0];
  args.erase(args.begin());
  try {
    if (command == "build") return relief::cli::run_build(args);
    if (command == "info") return relief::cli::run_info(args);
    if (command == "verify") return relief::cli::run_verify(args);
    if (command == "upgrade") return relief::cli::run_upgrade(args);
    if (command == "export") return relief::cli::run_export(args);
    if (command == "process") return relief::cli::run_process(args);
    if (command == "fuse") return relief::cli::run_fuse(args);
    if (command == "detect") return relief::cli::run_detect(args);
    if (command == "render") return relief::cli::run_render(args);
    if (command == "serve") return relief::cli::run_serve(args);
    if (command == "split") return relief::cli::run_split(args);
    if (command == "view") return relief::cli::run_view(args);
    if (command == "--version") {
      std::printf("relief 0.1.0\nallocator: %s\n", relief::cli::allocator_description().c_str());
      return 0;
    }
  } catch (const std::exception& e) {
    return relief::cli::report_error(std::string("internal error: ") + e.what());
  }
  relief::cli::report_error("unknown command '" + command + "' (see relief --help)");
  return 2;
}
