#include <csignal>
#include <cstdio>
#include <filesystem>

#include <fmt/format.h>

#include "allocator.h"
#include "args.h"
#include "commands.h"
#include "elevation_options.h"
#include "relief/serve/store_server.h"
#include "serve_web.h"

namespace relief::cli {

namespace {
constexpr const char* kServeHelp =
    R"(usage: relief serve STORE [--port P] [--bind ADDR] [--threads N] [--share I/N]
                    [--max-connections N] [--read-timeout S] [--write-timeout S]
                    [--web-root DIR] [--imagery STORE2] [--elevation STORE3
                    [--fuse first|mean] [--weights W,..]] [--elevation-op OP ...]
                    [--texture STORE4 [--texture-op OP ...] [--texture-range MIN,MAX]
                    [--texture-colormap grey|viridis]]

Serves a store read-only over HTTP/1.1 until interrupted: only the store's own
files (manifest.json, level indices, tiles) by their canonical paths, GET and
HEAD, keep-alive, Content-Length, ETag with If-None-Match, single byte
ranges, cache headers. Slow or idle clients cannot starve the others: each
connection has read and write deadlines.
Any static web server (nginx, ...) serving the store directory works the same.

An elevation store is also served to web clients (docs/web.md), tiles made on
request and cached, as relief render draws it (--elevation layers fused,
--elevation-op applied; the store's own files stay as they are):
  /terrain/layer.json, /terrain/{z}/{x}/{y}.terrain   Cesium quantized-mesh
  /terrain-rgb/{z}/{x}/{y}.png, /terrarium/...        MapLibre raster-dem
and imagery (an imagery STORE, --imagery STORE2, or one --texture layer: a
single-band store such as SAR through its operators, range and colour map
as relief render drapes it; relief render --help for the --texture family):
  /imagery/{z}/{x}/{y}.png                            Web Mercator XYZ
  /imagery/webp/{z}/{x}/{y}.webp                      the same, lossy WebP
  /imagery-geo/{z}/{x}/{y}.png                        Cesium's geographic tiling
each with its tiles.json;
and the pages that show it, with the libraries they load, from a web root:
  /view/#camera=LON,LAT,H,HEADING,PITCH,ROLL[&fov=DEG]   CesiumJS viewer
  /map/#camera=LON,LAT,H,HEADING,PITCH                    MapLibre GL JS map
  /lib/cesium/..., /lib/maplibre/...                     the npm packages

options:
  --port P       TCP port (default 8080; 0: any free port, printed)
  --bind ADDR    IPv4 address to listen on (default 127.0.0.1)
  --threads N    event-loop threads, each serving any number of connections
                 (default 16)
  --generate-threads N  threads that make web tiles (default one per core);
                 the event loops serve other requests meanwhile
  --share I/N    serve share I of a store spread over N servers: the tiles
                 whose Morton index modulo N is I (others get 404), the
                 manifest and level indices always. Readers name all N
                 servers in order: cyclic:http://a/,http://b/,...
  --max-connections N  connections open at once; more get 503 (default 1024,
                 lowered to fit the file-descriptor limit)
  --read-timeout S     a request head must arrive whole within S seconds of
                 the connection opening or the previous answer (default 10)
  --write-timeout S    an answer making no progress for S seconds is dropped
                 (default 10)
  --web-root DIR the pages' folder: view/ and node_modules/ as scripts/setup.sh
                 lays them out (npm ci --prefix web). Default: the source
                 tree's web/ when it exists, else the installed
                 share/relief/web; without one, /view/ gets 404
)";

// The web root: --web-root, else the source tree's web/ (a relief run from
// its build tree), else the installed copy; empty (with a note on stderr)
// when there is none, so the store is still served.
Result<std::filesystem::path> find_web_root(const std::optional<std::string>& given) {
  namespace fs = std::filesystem;
  std::error_code ec;
  if (given) {
    if (!fs::is_directory(*given, ec)) {
      return fail(fmt::format("serve: --web-root {}: not a directory", *given));
    }
    return fs::path(*given);
  }
  for (const fs::path candidate : {RELIEF_SOURCE_WEB_DIR, RELIEF_INSTALLED_WEB_DIR}) {
    if (fs::is_regular_file(candidate / "view/index.html", ec)) return candidate;
  }
  std::fprintf(stderr, "relief serve: no web root (--web-root DIR, %s or %s): /view/ answers 404\n",
               RELIEF_SOURCE_WEB_DIR, RELIEF_INSTALLED_WEB_DIR);
  return fs::path();
}

}  // namespace

int run_serve(const std::vector<std::string>& argv) {
  if (wants_help(argv)) return print_help(kServeHelp);
  give_up_huge_pages();
  // Repeatable and ordered: taken out before the other options are parsed.
  std::vector<std::string> rest = argv;
  auto elevation = take_elevation_processing(rest);
  if (!elevation) return report_error(elevation.error().message);
  auto textures = take_texture_layers(rest);
  if (!textures) return report_error(textures.error().message);
  std::vector<OptionSpec> specs = {
      {"--port"},          {"--bind"},  {"--threads"},  {"--max-connections"}, {"--read-timeout"},
      {"--write-timeout"}, {"--share"}, {"--web-root"}, {"--generate-threads"}};
  for (auto& spec : serve_web_options()) specs.push_back(spec);
  auto args = Args::parse(rest, specs, "serve");
  if (!args) return report_error(args.error().message);
  if (args->positional().size() != 1) return report_error("serve: expected exactly one STORE");
  serve::ServeOptions o;
  o.root = args->positional()[0];
  auto port = args->get_int("--port", 0, 65535);
  if (!port) return report_error(port.error().message);
  o.port = port->value_or(8080);
  if (auto b = args->get("--bind")) o.bind = *b;
  auto threads = args->get_int("--threads", 1, 1024);
  if (!threads) return report_error(threads.error().message);
  o.threads = threads->value_or(16);
  auto generators = args->get_int("--generate-threads", 1, 1024);
  if (!generators) return report_error(generators.error().message);
  o.generate_threads = generators->value_or(0);
  if (auto share = args->get("--share")) {
    const std::string_view form = "I/N with 0 <= I < N <= 4096";
    auto pair = parse_int_pair("--share", *share, '/', 0, 4096, form);
    if (pair && pair->first >= pair->second)
      pair = fail(fmt::format("--share: '{}' is not {}", *share, form));
    if (!pair) return report_error(pair.error().message);
    o.share_index = static_cast<unsigned>(pair->first);
    o.share_count = static_cast<unsigned>(pair->second);
  }
  auto connections = args->get_int("--max-connections", 1, 1 << 20);
  if (!connections) return report_error(connections.error().message);
  o.max_connections = connections->value_or(o.max_connections);
  for (auto [name, timeout] : {std::pair{"--read-timeout", &o.read_timeout},
                               std::pair{"--write-timeout", &o.write_timeout}}) {
    auto seconds = args->get_double(name);
    if (!seconds) return report_error(seconds.error().message);
    if (!*seconds) continue;
    if (!(**seconds >= 0.001 && **seconds <= 86400)) {
      return report_error(
          fmt::format("serve: {} {}: expected seconds in [0.001, 86400]", name, **seconds));
    }
    *timeout = std::chrono::milliseconds(static_cast<int64_t>(**seconds * 1000));
  }
  auto web_root = find_web_root(args->get("--web-root"));
  if (!web_root) return report_error(web_root.error().message);
  web::WebServiceOptions web_options;
  web_options.name = o.root.filename().empty() ? o.root.parent_path().filename().string()
                                               : o.root.filename().string();
  if (!web_root->empty()) {
    web_options.pages = web::web_root_mounts(*web_root);
    for (const auto& mount : web_options.pages) {
      if (std::filesystem::is_directory(mount.dir)) continue;
      std::fprintf(
          stderr,
          "relief serve: %s is missing: %s answers 404 (scripts/setup.sh --web installs it "
          "with npm ci --prefix web)\n",
          mount.dir.c_str(), mount.prefix.c_str());
    }
  }
  auto web = make_web_service(*args, o.root.string(), std::move(*elevation), *textures,
                              std::move(web_options));
  if (!web) return report_error(web.error().message);
  if (*web) {
    const auto as_generated = [](std::optional<web::WebAnswer> a) {
      if (!a) return std::optional<serve::GeneratedAnswer>{};
      return std::optional<serve::GeneratedAnswer>{serve::GeneratedAnswer{
          std::move(a->content_type), std::move(a->content_encoding), std::move(a->body)}};
    };
    o.generate = [web = *web, as_generated](std::string_view target) {
      return as_generated(web->answer(target));
    };
    o.generate_at_once = [web = *web, as_generated](std::string_view target) {
      return as_generated(web->answer_if_made(target));
    };
  }
  // Block the stop signals before the server's threads start, so only the
  // main thread receives them (sigwait below).
  sigset_t stop_signals;
  sigemptyset(&stop_signals);
  sigaddset(&stop_signals, SIGINT);
  sigaddset(&stop_signals, SIGTERM);
  pthread_sigmask(SIG_BLOCK, &stop_signals, nullptr);
  auto server = serve::StoreServer::start(o);
  if (!server) return report_error(server.error().message);
  std::printf("serving %s on http://%s:%d/", o.root.c_str(), o.bind.c_str(), (*server)->port());
  if (o.share_count > 1) std::printf(" (share %u/%u)", o.share_index, o.share_count);
  std::printf("\n");
  if (!web_root->empty()) {
    std::printf("pages from %s: http://%s:%d/view/\n", web_root->c_str(), o.bind.c_str(),
                (*server)->port());
  }
  std::fflush(stdout);
  int signal = 0;
  sigwait(&stop_signals, &signal);
  (*server)->stop();
  return 0;
}

}  // namespace relief::cli
