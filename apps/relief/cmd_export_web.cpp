#include <algorithm>
#include <atomic>
#include <cstdio>
#include <filesystem>
#include <functional>
#include <system_error>

#include <fmt/format.h>

#include "commands.h"
#include "export_web.h"
#include "output_safety.h"
#include "relief/base/file_io.h"
#include "relief/base/first_error.h"
#include "relief/base/parallel.h"
#include "relief/base/progress.h"
#include "relief/tiles/store.h"
#include "relief/web/raster_tiles.h"
#include "relief/web/terrain_tiler.h"
#include "render_setup.h"

namespace relief::cli {
namespace {

namespace fs = std::filesystem;

constexpr const char* kFormats = "geotiff, quantized-mesh, terrain-rgb, terrarium, xyz, xyz-webp";
constexpr uint64_t kCacheBytes = uint64_t{256} << 20;

Result<std::optional<geo::GeoBox>> parse_web_bbox(const Args& args) {
  auto b = args.get("--bbox");
  if (!b) return std::nullopt;
  auto v = RELIEF_TRY(parse_numbers("--bbox", *b, 4));
  if (!(v[0] < v[2] && v[1] < v[3]))
    return fail(fmt::format("--bbox: '{}' is not W,S,E,N with W < E and S < N", *b));
  return geo::GeoBox{v[0], v[1], v[2], v[3]};
}

// Options of one format given to another: an error rather than ignored.
Status refuse_options_of_other_formats(const Args& args, const std::string& format,
                                       std::initializer_list<const char*> options) {
  for (const char* option : options) {
    if (args.has(option))
      return fail(fmt::format("export: {} does not apply to --format {}", option, format));
  }
  return {};
}

Result<web::TerrainOptions> terrain_options(const Args& args) {
  RELIEF_CHECK(
      refuse_options_of_other_formats(args, "quantized-mesh", {"--tile-size", "--max-zoom"}));
  web::TerrainOptions o;
  auto max_level = RELIEF_TRY(args.get_int("--max-level", 0, geo::kMaxLevel));
  if (max_level) o.max_level = *max_level;
  auto max_error = RELIEF_TRY(args.get_double("--max-error"));
  if (max_error) {
    if (!(*max_error >= 0) || *max_error > 1e7) {
      return fail(fmt::format("--max-error: '{}' is not a height in metres >= 0",
                              *args.get("--max-error")));
    }
    o.max_error = static_cast<float>(*max_error);
  }
  o.bbox = RELIEF_TRY(parse_web_bbox(args));
  o.cache_bytes = kCacheBytes;
  return o;
}

Result<web::RasterTileOptions> raster_options(const Args& args, const std::string& format) {
  RELIEF_CHECK(refuse_options_of_other_formats(args, format, {"--max-level", "--max-error"}));
  web::RasterTileOptions o;
  if (auto size = args.get("--tile-size")) {
    if (*size != "256" && *size != "512")
      return fail(fmt::format("--tile-size: '{}' is not 256 or 512", *size));
    o.tile_size = std::stoi(*size);
  }
  auto max_zoom = RELIEF_TRY(args.get_int("--max-zoom", 0, web::kMaxZoom));
  if (max_zoom) o.max_zoom = *max_zoom;
  o.bbox = RELIEF_TRY(parse_web_bbox(args));
  o.cache_bytes = kCacheBytes;
  return o;
}

// What one format writes: the tiles of each zoom and the file describing them.
struct TileSet {
  std::vector<std::vector<geo::TileKey>> zooms;  // (z, x, y) in Z-order
  std::function<Result<std::vector<std::byte>>(const geo::TileKey&)> make;
  std::string extension;  // "terrain", "png"
  std::string index_name, index_text;
};

// Tiles in Z-order, so that neighbouring tiles (which read the same store
// tiles) are made close together in time and the decoded-tile cache holds.
void sort_z_order(std::vector<geo::TileKey>& keys) {
  std::sort(keys.begin(), keys.end(),
            [](const auto& a, const auto& b) { return a.morton() < b.morton(); });
}

// Writes every tile and the index under `dir`.
Status write_tiles(const TileSet& set, const fs::path& dir, unsigned threads, Progress& progress,
                   uint64_t& tiles, uint64_t& bytes) {
  uint64_t total = 0;
  for (const auto& keys : set.zooms) total += keys.size();
  ThreadExecutor executor(threads);
  FirstError first;
  std::atomic<uint64_t> written{0};
  progress.begin(set.extension + " tiles", total);
  for (const auto& keys : set.zooms) {
    executor.parallel_for(keys.size(), [&](size_t i) {
      if (first.failed()) return;
      const geo::TileKey& k = keys[i];
      auto body = set.make(k);
      Status done =
          body ? write_file_atomic(
                     dir / fmt::format("{}/{}/{}.{}", k.level, k.x, k.y, set.extension), *body)
               : Status(std::unexpected(body.error()));
      if (!done) return first.set(done.error());
      written += body->size();
      progress.advance();
    });
    if (first.failed()) break;
  }
  progress.end();
  RELIEF_CHECK(first.status());
  tiles = total;
  bytes = written;
  return write_text_file_atomic(dir / set.index_name, set.index_text, false);
}

TileSet terrain_tiles(const web::TerrainTiler& tiler, const std::string& name) {
  TileSet set;
  for (int level = 0; level <= tiler.max_level(); ++level) {
    std::vector<geo::TileKey>& keys = set.zooms.emplace_back();
    for (const web::TerrainKey& k : tiler.available_tiles(level))
      keys.push_back({k.level, k.x, k.y});
    sort_z_order(keys);
  }
  set.make = [&tiler](const geo::TileKey& k) { return tiler.tile({k.level, k.x, k.y}); };
  set.extension = "terrain";
  set.index_name = "layer.json";
  set.index_text = tiler.layer_json(name);
  return set;
}

// `webp`: imagery as WebP (xyz-webp) rather than PNG.
TileSet raster_tiles(const web::RasterTiler& tiler, const std::string& name,
                     std::optional<web::DemEncoding> encoding, bool webp) {
  TileSet set;
  for (int z = 0; z <= tiler.max_zoom(); ++z) {
    std::vector<geo::TileKey>& keys = set.zooms.emplace_back();
    for (const web::XyzKey& k : tiler.available_tiles(z)) keys.push_back({k.z, k.x, k.y});
    sort_z_order(keys);
  }
  set.make = [&tiler, encoding, webp](const geo::TileKey& k) {
    const web::XyzKey key{k.level, k.x, k.y};
    if (encoding) return tiler.dem_png_tile(key, *encoding);
    return webp ? tiler.imagery_webp_tile(key) : tiler.imagery_png_tile(key);
  };
  set.extension = webp ? "webp" : "png";
  set.index_name = "tiles.json";
  set.index_text = tiler.tile_json(name, encoding, set.extension);
  return set;
}

// An earlier web export (of any format) is replaced; anything else at the
// path is refused before any work.
Status check_destination(const fs::path& out) {
  std::error_code ec;
  if (!fs::exists(fs::symlink_status(out, ec))) return {};
  if (fs::is_directory(out, ec) && (fs::exists(out / "layer.json", ec) ||
                                    fs::exists(out / "tiles.json", ec) || fs::is_empty(out, ec))) {
    return {};
  }
  return fail(fmt::format(
      "-o: '{}' exists and is not an earlier web tile export (no layer.json or tiles.json)",
      out.string()));
}

Status move_into_place(const fs::path& staged, const fs::path& out) {
  std::error_code ec;
  if (fs::exists(fs::symlink_status(out, ec))) {
    const fs::path old = temporary_name(out) + ".old";
    fs::rename(out, old, ec);
    if (ec) return fail(fmt::format("-o: cannot replace '{}': {}", out.string(), ec.message()));
    fs::rename(staged, out, ec);
    if (ec)
      return fail(
          fmt::format("-o: cannot move the export to '{}': {}", out.string(), ec.message()));
    fs::remove_all(old, ec);
    return {};
  }
  fs::rename(staged, out, ec);
  if (ec)
    return fail(fmt::format("-o: cannot move the export to '{}': {}", out.string(), ec.message()));
  return {};
}

// The tiler of `format` for the store: a terrain or a raster tiler, and
// the tiles it writes (which refer to it).
struct Tilers {
  std::optional<web::TerrainTiler> terrain;
  std::optional<web::RasterTiler> raster;
  int max_zoom = 0;
};

Result<Tilers> make_tilers(const Args& args, const std::string& format, tiles::Store store) {
  auto shared = std::make_shared<const tiles::Store>(std::move(store));
  const auto kind = shared->manifest().kind;
  Tilers t;
  if (format == "quantized-mesh") {
    const web::TerrainOptions options = RELIEF_TRY(terrain_options(args));
    t.terrain.emplace(RELIEF_TRY(web::TerrainTiler::create(shared, options)));
    t.max_zoom = t.terrain->max_level();
    return t;
  }
  const bool dem = format != "xyz" && format != "xyz-webp";
  if (dem != (kind == tiles::DatasetKind::Elevation)) {
    return fail(
        fmt::format("--format {}: {} holds {}; {} (use --format {})", format,
                    shared->root().string(), tiles::to_string(kind),
                    dem ? "Terrain-RGB and Terrarium encode the heights of an elevation store"
                        : "xyz tiles are the colours of an imagery store",
                    dem ? "xyz for imagery" : "terrain-rgb or terrarium for elevation"));
  }
  const web::RasterTileOptions options = RELIEF_TRY(raster_options(args, format));
  if (options.bbox && !options.bbox->intersects(shared->manifest().extent)) {
    return fail(fmt::format("--bbox: '{}' does not meet the extent of {}", *args.get("--bbox"),
                            shared->root().string()));
  }
  t.raster.emplace(RELIEF_TRY(web::RasterTiler::create(shared, options)));
  t.max_zoom = t.raster->max_zoom();
  return t;
}

// The store as relief render draws it: an elevation store with its
// --elevation layers fused and its --elevation-op chain applied.
Result<tiles::Store> open_web_input(const Args& args, const std::string& input,
                                    pipeline::ElevationProcessing elevation) {
  tiles::Store store = RELIEF_TRY(open_store(input));
  if (store.manifest().kind == tiles::DatasetKind::Elevation) {
    return open_elevation(args, input, std::move(elevation));
  }
  if (!elevation.empty() || !args.get_all("--elevation").empty()) {
    return fail(
        fmt::format("export: {} holds {}: --elevation and --elevation-op need an "
                    "elevation STORE",
                    input, tiles::to_string(store.manifest().kind)));
  }
  return store;
}

}  // namespace

int run_export_web(const Args& args, const std::string& format,
                   pipeline::ElevationProcessing elevation) {
  const auto encoding = web::dem_encoding_from_format(format);
  if (format != "quantized-mesh" && format != "xyz" && format != "xyz-webp" && !encoding) {
    return report_error(fmt::format("--format: '{}' is not one of {}", format, kFormats));
  }
  const std::string input = args.positional()[0];
  auto threads = args.get_int("--threads", 1, 1024);
  if (!threads) return report_error(threads.error().message);
  if (!args.get("--output")) return report_error("export: -o DIR is required");
  const fs::path out = *args.get("--output");
  std::vector<std::string> inputs = args.get_all("--elevation");
  inputs.push_back(input);
  if (auto safe = check_outputs_spare_inputs({{"-o", out.string(), OutputKind::Store}}, inputs);
      !safe) {
    return report_error(safe.error().message);
  }
  if (auto ok = check_destination(out); !ok) return report_error(ok.error().message);
  auto store = open_web_input(args, input, std::move(elevation));
  if (!store) return report_error(store.error().message);
  auto tilers = make_tilers(args, format, std::move(*store));
  if (!tilers) return report_error(tilers.error().message);

  (void)remove_stale_temporaries_of(out);
  const fs::path staged = temporary_name(out);
  auto progress =
      args.has("--quiet") ? std::make_unique<NullProgress>() : make_progress_for_stderr();
  const std::string name = fs::path(input).filename().empty()
                               ? fs::path(input).parent_path().filename().string()
                               : fs::path(input).filename().string();
  const TileSet set = tilers->terrain
                          ? terrain_tiles(*tilers->terrain, name)
                          : raster_tiles(*tilers->raster, name, encoding, format == "xyz-webp");
  uint64_t tiles = 0, bytes = 0;
  Status done = write_tiles(set, staged, threads->value_or(0), *progress, tiles, bytes);
  if (done) done = move_into_place(staged, out);
  if (!done) {
    std::error_code ec;
    fs::remove_all(staged, ec);
    return report_error(done.error().message);
  }
  std::printf("wrote %s: %llu %s tiles, %s 0-%d, %.1f MiB\n", out.c_str(),
              static_cast<unsigned long long>(tiles), format.c_str(),
              tilers->terrain ? "levels" : "zooms", tilers->max_zoom,
              static_cast<double>(bytes) / (1 << 20));
  return 0;
}

}  // namespace relief::cli
