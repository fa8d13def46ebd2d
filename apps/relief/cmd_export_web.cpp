#include <algorithm>
#include <atomic>
#include <cstdio>
#include <filesystem>
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
#include "relief/web/terrain_tiler.h"

namespace relief::cli {
namespace {

namespace fs = std::filesystem;

Result<web::TerrainOptions> terrain_options(const Args& args) {
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
  if (auto b = args.get("--bbox")) {
    auto v = RELIEF_TRY(parse_numbers("--bbox", *b, 4));
    if (!(v[0] < v[2] && v[1] < v[3]))
      return fail(fmt::format("--bbox: '{}' is not W,S,E,N with W < E and S < N", *b));
    o.bbox = geo::GeoBox{v[0], v[1], v[2], v[3]};
  }
  o.cache_bytes = uint64_t{256} << 20;
  return o;
}

// Tiles in Z-order, so that neighbouring tiles (which read the same store
// tiles) are made close together in time and the decoded-tile cache holds.
void sort_z_order(std::vector<web::TerrainKey>& keys) {
  const auto morton = [](const web::TerrainKey& k) {
    return geo::TileKey{k.level, k.x, k.y}.morton();
  };
  std::sort(keys.begin(), keys.end(),
            [&](const auto& a, const auto& b) { return morton(a) < morton(b); });
}

// Writes every tile and layer.json under `dir`.
Status write_terrain(const web::TerrainTiler& tiler, const fs::path& dir, const std::string& name,
                     unsigned threads, Progress& progress, uint64_t& tiles, uint64_t& bytes) {
  std::vector<std::vector<web::TerrainKey>> levels;
  uint64_t total = 0;
  for (int level = 0; level <= tiler.max_level(); ++level) {
    levels.push_back(tiler.available_tiles(level));
    sort_z_order(levels.back());
    total += levels.back().size();
  }
  ThreadExecutor executor(threads);
  FirstError first;
  std::atomic<uint64_t> written{0};
  progress.begin("terrain tiles", total);
  for (const auto& keys : levels) {
    executor.parallel_for(keys.size(), [&](size_t i) {
      if (first.failed()) return;
      const web::TerrainKey& k = keys[i];
      auto body = tiler.tile(k);
      Status done =
          body ? write_file_atomic(dir / fmt::format("{}/{}/{}.terrain", k.level, k.x, k.y), *body)
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
  return write_text_file_atomic(dir / "layer.json", tiler.layer_json(name), false);
}

// Moves the finished export into place: an earlier export of the same kind
// is replaced, anything else at the path is refused before any work.
Status check_destination(const fs::path& out) {
  std::error_code ec;
  if (!fs::exists(fs::symlink_status(out, ec))) return {};
  if (fs::is_directory(out, ec) && fs::exists(out / "layer.json", ec)) return {};
  if (fs::is_directory(out, ec) && fs::is_empty(out, ec)) return {};
  return fail(fmt::format("-o: '{}' exists and is not an earlier terrain export (no layer.json)",
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

}  // namespace

int run_export_web(const Args& args, const std::string& format) {
  if (format != "quantized-mesh") {
    return report_error(
        fmt::format("--format: '{}' is not one of geotiff, quantized-mesh", format));
  }
  const std::string input = args.positional()[0];
  auto options = terrain_options(args);
  if (!options) return report_error(options.error().message);
  auto threads = args.get_int("--threads", 1, 1024);
  if (!threads) return report_error(threads.error().message);
  if (!args.get("--output")) return report_error("export: -o DIR is required");
  const fs::path out = *args.get("--output");
  if (auto safe = check_outputs_spare_inputs({{"-o", out.string(), OutputKind::Store}}, {input});
      !safe) {
    return report_error(safe.error().message);
  }
  if (auto ok = check_destination(out); !ok) return report_error(ok.error().message);
  auto store = tiles::Store::open(input);
  if (!store) return report_error(store.error().message);
  auto tiler =
      web::TerrainTiler::create(std::make_shared<const tiles::Store>(std::move(*store)), *options);
  if (!tiler) return report_error(tiler.error().message);

  (void)remove_stale_temporaries_of(out);
  const fs::path staged = temporary_name(out);
  auto progress =
      args.has("--quiet") ? std::make_unique<NullProgress>() : make_progress_for_stderr();
  uint64_t tiles = 0, bytes = 0;
  const std::string name = fs::path(input).filename().empty()
                               ? fs::path(input).parent_path().filename().string()
                               : fs::path(input).filename().string();
  Status done = write_terrain(*tiler, staged, name, threads->value_or(0), *progress, tiles, bytes);
  if (done) done = move_into_place(staged, out);
  if (!done) {
    std::error_code ec;
    fs::remove_all(staged, ec);
    return report_error(done.error().message);
  }
  std::printf("wrote %s: %llu quantized-mesh tiles, levels 0-%d, %.1f MiB\n", out.c_str(),
              static_cast<unsigned long long>(tiles), tiler->max_level(),
              static_cast<double>(bytes) / (1 << 20));
  return 0;
}

}  // namespace relief::cli
