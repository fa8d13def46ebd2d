#include "render_path.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <unordered_set>

#include <fmt/format.h>
#include <nlohmann/json.hpp>

#include "commands.h"
#include "relief/base/file_io.h"
#include "relief/base/memory_use.h"
#include "relief/base/units.h"
#include "relief/lod/camera_path.h"
#include "relief/render/terrain_renderer.h"
#include "relief/stream/radius_pager.h"
#include "relief/stream/tile_loader.h"

namespace relief::cli {

namespace {

using nlohmann::json;

// A path longer than this many frames is refused unless --max-frames allows
// it: a typo in a keyframe's time (1e12 s) must not render until killed.
constexpr int kDefaultMaxFrames = 100000;

struct PathOptions {
  bool interactive = true;
  double fps = 0;  // 0: the path's
  stream::LoaderOptions loader;
  uint64_t imagery_budget = uint64_t{512} << 20;  // the imagery loader's L2
  bool prefetch = true;
  double radius = 0;  // > 0: the radius pager
  double until_complete = 0;
  int max_frames = kDefaultMaxFrames;
  std::string events, stats;
  bool frames = true;
};

Result<PathOptions> parse_path_options(const Args& args) {
  PathOptions o;
  o.loader.memory_budget = uint64_t{512} << 20;
  if (auto mode = args.get("--mode")) {
    if (*mode != "interactive" && *mode != "complete") {
      return fail("--mode: '" + *mode + "' is neither interactive nor complete");
    }
    o.interactive = *mode == "interactive";
  }
  if (auto fps = RELIEF_TRY(args.get_double("--fps"))) {
    if (!(*fps > 0 && *fps <= 1000)) return fail("--fps: must be in (0, 1000]");
    o.fps = *fps;
  }
  for (auto [name, budget] : {std::pair{"--memory-budget", &o.loader.memory_budget},
                              std::pair{"--imagery-budget", &o.imagery_budget}}) {
    if (auto size = args.get(name)) {
      auto bytes = parse_byte_size(*size);
      if (!bytes) return fail(fmt::format("{}: {}", name, bytes.error().message));
      *budget = *bytes;
    }
  }
  if (auto loads = RELIEF_TRY(args.get_int("--loads", 1, 256))) o.loader.max_in_flight = *loads;
  o.prefetch = !args.has("--no-prefetch");
  if (auto pager = args.get("--pager"); pager && *pager != "priority") {
    char end = 0;
    if (std::sscanf(pager->c_str(), "radius:%lf%c", &o.radius, &end) != 1 || !(o.radius > 0)) {
      return fail("--pager: '" + *pager + "' is neither priority nor radius:K with K > 0");
    }
  }
  if (auto s = RELIEF_TRY(args.get_double("--until-complete"))) {
    if (!(*s >= 0 && *s <= 3600)) return fail("--until-complete: must be in [0, 3600] s");
    o.until_complete = *s;
  }
  if (auto n = RELIEF_TRY(args.get_int("--max-frames", 1, 100000000))) o.max_frames = *n;
  o.events = args.get("--events").value_or("");
  o.stats = args.get("--stats").value_or("");
  o.frames = !args.has("--no-frames");
  return o;
}

// {"fps": N, "keyframes": [{"time": T, "camera": [6 numbers], "cut": bool}, ...]}
Result<std::pair<std::vector<lod::Keyframe>, double>> read_path(const std::string& path,
                                                                const RenderSetup& s) {
  auto bytes = RELIEF_TRY(read_file(path));
  json doc =
      json::parse(reinterpret_cast<const char*>(bytes.data()),
                  reinterpret_cast<const char*>(bytes.data()) + bytes.size(), nullptr, false);
  if (doc.is_discarded() || !doc.is_object()) return fail(path + ": not a JSON object");
  double fps = 30;
  if (doc.contains("fps")) {
    if (!doc["fps"].is_number() || !(doc["fps"].get<double>() > 0)) {
      return fail(path + ": \"fps\" must be a number > 0");
    }
    fps = doc["fps"].get<double>();
  }
  if (!doc.contains("keyframes") || !doc["keyframes"].is_array() || doc["keyframes"].empty()) {
    return fail(path + ": needs a non-empty \"keyframes\" array");
  }
  std::vector<lod::Keyframe> keys;
  for (size_t i = 0; i < doc["keyframes"].size(); ++i) {
    const json& k = doc["keyframes"][i];
    const std::string where = fmt::format("{}: keyframe {}", path, i);
    if (!k.is_object() || !k.contains("time") || !k["time"].is_number() || !k.contains("camera") ||
        !k["camera"].is_array() || k["camera"].size() != 6) {
      return fail(where +
                  ": needs \"time\" and \"camera\": [lon, lat, height, heading, pitch, roll]");
    }
    std::vector<double> c(6);
    for (size_t j = 0; j < 6; ++j) {
      if (!k["camera"][j].is_number()) return fail(where + ": camera values must be numbers");
      c[j] = k["camera"][j].get<double>();
    }
    lod::Keyframe key;
    key.time = k["time"].get<double>();
    if (!std::isfinite(key.time)) return fail(where + ": \"time\" must be finite");
    key.camera = RELIEF_TRY(camera_from_values(where, c, s));
    key.cut = k.value("cut", false);
    if (!keys.empty() && !(key.time > keys.back().time)) {
      return fail(where + ": times must increase");
    }
    if (auto view = lod::make_view(key.camera); !view)
      return fail(where + ": " + view.error().message);
    keys.push_back(key);
  }
  return std::pair{std::move(keys), fps};
}

// Where the camera will be `frames` frames from now at its present motion.
lod::Camera extrapolate(const lod::Camera& prev, const lod::Camera& now, double frames) {
  auto step = [&](double a, double b, bool angle) {
    const double d = angle ? std::remainder(b - a, 360.0) : b - a;
    return b + d * frames;
  };
  lod::Camera c = now;
  c.lon = std::remainder(step(prev.lon, now.lon, true), 360.0);
  c.lat = std::clamp(step(prev.lat, now.lat, false), -89.9, 89.9);
  c.height = std::max(now.height * 0.5, step(prev.height, now.height, false));
  c.heading = std::remainder(step(prev.heading, now.heading, true), 360.0);
  c.pitch = std::clamp(step(prev.pitch, now.pitch, false), -90.0, 90.0);
  return c;
}

double percentile(std::vector<double> v, double p) {
  if (v.empty()) return 0;
  std::sort(v.begin(), v.end());
  const size_t i =
      std::min(v.size() - 1, static_cast<size_t>(std::ceil(p * static_cast<double>(v.size()))) - 1);
  return v[i];
}

json loader_json(const stream::LoaderStats& s) {
  json levels = json::object();
  for (size_t l = 0; l < s.resident_per_level.size(); ++l) {
    if (s.resident_per_level[l].tiles) {
      levels[std::to_string(l)] = {{"tiles", s.resident_per_level[l].tiles},
                                   {"bytes", s.resident_per_level[l].bytes}};
    }
  }
  return {{"resident_tiles", s.resident_tiles},
          {"resident_bytes", s.resident_bytes},
          {"budget_bytes", s.memory_budget},
          {"pinned_bytes", s.pinned_bytes},
          {"resident_per_level", levels},
          {"queued", s.queued},
          {"in_flight", s.in_flight},
          {"hits", s.hits},
          {"misses", s.misses},
          {"requested", s.requested},
          {"loaded", s.loaded},
          {"failed", s.failed},
          {"evicted", s.evicted},
          {"cancelled", s.cancelled},
          {"bytes_fetched", s.bytes_fetched},
          {"prefetched", s.prefetched},
          {"prefetch_used", s.prefetch_used}};
}

using TileSet = std::unordered_set<geo::TileKey, geo::TileKeyHash>;

// Adds the data tiles a selection draws (own and parent data) to `tiles`;
// with `ancestors`, also the tiles above them, which a coarse-first loader
// must have fetched before.
void add_drawn(TileSet& tiles, lod::TerrainModel& terrain, const lod::Selection& selection,
               bool ancestors) {
  for (const auto& q : selection.quads) {
    for (const auto& w : {terrain.window(q.key), terrain.parent_window(q.key)}) {
      if (!w.tile) continue;
      for (std::optional<geo::TileKey> k = *w.tile; k; k = ancestors ? k->parent() : std::nullopt) {
        if (!tiles.insert(*k).second && ancestors) break;  // its ancestors are in already
      }
    }
  }
}

uint64_t file_bytes(const tiles::Store& store, const TileSet& tiles) {
  uint64_t bytes = 0;
  for (const auto& k : tiles) {
    if (const auto* e = store.index(k.level).find(k)) bytes += e->file_bytes;
  }
  return bytes;
}

// File bytes of the data tiles a selection draws, and of level 0.
uint64_t view_bytes(const tiles::Store& store, lod::TerrainModel& terrain,
                    const lod::Selection& selection) {
  TileSet tiles;
  for (const tiles::IndexEntry& e : store.index(0).entries()) tiles.insert(e.key);
  add_drawn(tiles, terrain, selection, false);
  return file_bytes(store, tiles);
}

}  // namespace

int render_path(const Args& args, RenderSetup& setup, const Clock& clock) {
  auto options = parse_path_options(args);
  if (!options) return report_error(options.error().message);
  if (setup.full_resolution) return report_error("--full-resolution: for stills only, not --path");
  auto path = read_path(*args.get("--path"), setup);
  if (!path) return report_error(path.error().message);
  const auto& [keys, path_fps] = *path;
  const double fps = options->fps > 0 ? options->fps : path_fps;
  const double duration = keys.back().time - keys.front().time;
  // In double: a huge duration must not overflow the frame count.
  const double frame_count = std::floor(duration * fps + 1e-9) + 1;
  if (!(frame_count <= options->max_frames)) {
    return report_error(
        fmt::format("{}: {:.6g} s at {:g} fps is {:.6g} frames, more than "
                    "--max-frames {} (raise it for longer paths)",
                    *args.get("--path"), duration, fps, frame_count, options->max_frames));
  }
  const auto path_frames = static_cast<size_t>(frame_count);
  const std::string out = *args.get("--output");
  if (options->frames) {
    std::error_code ec;
    std::filesystem::create_directories(out, ec);
    if (ec) return report_error(out + ": cannot create the frame directory: " + ec.message());
  }

  const tiles::Store& store = setup.store;
  const lod::MeshTopology mesh(setup.mesh_level);
  std::unique_ptr<stream::TileLoader> loader, imagery_loader;
  std::unique_ptr<lod::TerrainModel> terrain;
  json events = json::array();
  size_t frame_index = 0;
  if (options->interactive) {
    auto l = stream::TileLoader::create(store, options->loader);
    if (!l) return report_error(l.error().message);
    loader = std::move(*l);
    terrain = std::make_unique<lod::TerrainModel>(store, mesh, *loader);
    if (setup.imagery) {
      stream::LoaderOptions io = options->loader;
      io.memory_budget = options->imagery_budget;
      auto il = stream::TileLoader::create(*setup.imagery, io);
      if (!il) return report_error(il.error().message);
      imagery_loader = std::move(*il);
    }
    if (!options->events.empty()) {
      loader->subscribe([&](const stream::TileEvent& e) {
        events.push_back({{"frame", frame_index},
                          {"event", stream::to_string(e.kind)},
                          {"tile", e.key.to_string()},
                          {"bytes", e.bytes},
                          {"prefetch", e.prefetch},
                          {"error", e.error}});
      });
    }
  } else {
    terrain = std::make_unique<lod::TerrainModel>(&store, mesh, options->loader.memory_budget);
  }

  auto context = render::GlContext::create_headless();
  if (!context) return report_error(context.error().message);
  auto target = render::make_offscreen_target(setup.width, setup.height);
  if (!target) return report_error(target.error().message);
  auto renderer = render::TerrainRenderer::create(
      *terrain, setup.imagery ? &*setup.imagery : nullptr, setup.gpu_budget, imagery_loader.get());
  if (!renderer) return report_error(renderer.error().message);
  render::RenderOptions ro;
  ro.exaggeration = static_cast<float>(setup.exaggeration);
  ro.sky = setup.sky;
  const lod::SelectionOptions so = selection_options(setup);

  const double lookahead = 0.5 * fps;  // prefetch half a second ahead
  json frames = json::array();
  std::vector<double> frame_ms, cpu_ms;
  std::vector<std::pair<size_t, double>> cuts;  // frame, time of each cut
  for (size_t k = 1; k < keys.size(); ++k) {
    if (keys[k].cut) cuts.emplace_back(0, keys[k].time);
  }
  const auto start = clock.now();
  lod::Camera previous = keys.front().camera;
  bool complete = false;
  TileSet drawn;                // every data tile any frame drew, with its ancestors
  uint64_t imagery_misses = 0;  // a frame that missed imagery is not complete
  double settle_start = -1;
  lod::Selection last;
  for (frame_index = 0;; ++frame_index) {
    const bool on_path = frame_index < path_frames;
    if (!on_path) {
      if (!options->interactive || complete) break;
      const double now = seconds_between(start, clock.now());
      if (settle_start < 0) settle_start = now;
      if (now - settle_start >= options->until_complete) break;
    }
    const double t =
        keys.front().time + static_cast<double>(std::min(frame_index, path_frames - 1)) / fps;
    const lod::Camera camera = lod::camera_at(keys, t);
    auto view = lod::make_view(camera);
    if (!view) return report_error(fmt::format("frame {}: {}", frame_index, view.error().message));

    const auto frame_start = clock.now();
    terrain->begin_frame();
    auto selection = lod::select_quads(*view, *terrain, so);
    if (!selection) return report_error(selection.error().message);
    if (loader && options->prefetch && frame_index > 0) {
      const bool jumped =
          std::abs(camera.lon - previous.lon) + std::abs(camera.lat - previous.lat) > 1;
      if (!jumped && (camera.lon != previous.lon || camera.lat != previous.lat ||
                      camera.height != previous.height || camera.heading != previous.heading ||
                      camera.pitch != previous.pitch)) {
        if (auto ahead = lod::make_view(extrapolate(previous, camera, lookahead))) {
          loader->set_prefetch(true);
          auto predicted = lod::select_quads(*ahead, *terrain, so);
          loader->set_prefetch(false);
          if (!predicted) return report_error(predicted.error().message);
        }
      }
    }
    if (loader && options->radius > 0) {
      loader->begin_frame();  // the pager's requests replace the view's
      auto n = stream::request_radius(*terrain, store, view->eye, options->radius);
      if (!n) return report_error(n.error().message);
    }
    terrain->end_frame();
    if (imagery_loader) imagery_loader->begin_frame();  // the renderer requests imagery
    add_drawn(drawn, *terrain, *selection, true);
    auto frame = (*renderer)->draw(*view, *selection, **target, ro);
    if (imagery_loader) imagery_loader->end_frame();
    if (!frame) return report_error(frame.error().message);
    const double ms = seconds_between(frame_start, clock.now()) * 1e3;
    complete = selection->stats.waiting == 0;
    frame_ms.push_back(ms);
    cpu_ms.push_back(ms - frame->gpu_seconds * 1e3);
    for (auto& [frame_of_cut, time] : cuts) {
      if (!frame_of_cut && t >= time) frame_of_cut = frame_index + 1;  // 1-based: 0 = not yet
    }

    json f = {{"frame", frame_index},
              {"time", seconds_between(start, frame_start)},
              {"camera",
               {camera.lon, camera.lat, camera.height, camera.heading, camera.pitch, camera.roll}},
              {"frame_ms", ms},
              {"cpu_ms", cpu_ms.back()},
              {"selection_ms", selection->stats.seconds * 1e3},
              {"draw_ms", (frame->prepare_seconds + frame->gpu_seconds) * 1e3},
              {"quads", selection->stats.quads},
              {"triangles", frame->triangles},
              {"triangles_per_pixel", frame->triangles_per_pixel()},
              {"draw_calls", frame->draw_calls},
              {"uploaded_bytes",
               {{"geometry", frame->geometry_bytes}, {"textures", frame->texture_bytes}}},
              {"waiting_quads", selection->stats.waiting},
              {"complete", complete},
              {"gpu",
               {{"textures", frame->gpu_textures},
                {"bytes", frame->gpu_bytes},
                {"budget_bytes", frame->gpu_budget},
                {"slots", frame->gpu_slots},
                {"allocated_bytes", frame->gpu_allocated_bytes},
                {"uploads", frame->uploads},
                {"evicted", frame->gpu_evicted}}},
              {"rss_bytes", resident_set_bytes()},
              {"exact_errors",
               {{"measured", terrain->error_counts().measured},
                {"prepared", terrain->error_counts().prepared}}}};
    if (loader) f["memory"] = loader_json(loader->stats());
    if (setup.disk_cache) {
      const net::DiskCacheStats d = setup.disk_cache->stats();
      f["disk_cache"] = {{"bytes", d.bytes},         {"budget_bytes", setup.disk_cache_budget},
                         {"hits", d.hits},           {"misses", d.misses},
                         {"evictions", d.evictions}, {"shared", d.shared},
                         {"repaired", d.repaired}};
    }
    if (imagery_loader) {
      const stream::LoaderStats is = imagery_loader->stats();
      f["imagery_memory"] = loader_json(is);
      complete = complete && is.queued == 0 && is.in_flight == 0 && is.misses == imagery_misses;
      imagery_misses = is.misses;
      f["complete"] = complete;
    }
    frames.push_back(std::move(f));

    if (options->frames) {
      auto pixels = (*target)->read_rgba();
      if (!pixels) return report_error(pixels.error().message);
      const std::string file =
          (std::filesystem::path(out) / fmt::format("frame_{:05d}.png", frame_index)).string();
      if (auto st = write_png(file, *pixels, setup.width, setup.height); !st) {
        return report_error(st.error().message);
      }
    }
    last = std::move(*selection);
    previous = camera;
    if (options->interactive) {  // real time: the next frame is due 1/fps after this one
      clock.sleep_until(frame_start + std::chrono::duration_cast<Clock::Duration>(
                                          std::chrono::duration<double>(1 / fps)));
    }
  }

  // Time from each cut until the first complete frame after it.
  json cut_json = json::array();
  for (const auto& [frame_of_cut, time] : cuts) {
    if (!frame_of_cut) continue;
    const double t0 = frames[frame_of_cut - 1]["time"].get<double>();
    json c = {{"frame", frame_of_cut - 1}, {"complete_after_s", nullptr}};
    for (size_t i = frame_of_cut - 1; i < frames.size(); ++i) {
      if (frames[i]["complete"].get<bool>()) {
        c["complete_after_s"] = frames[i]["time"].get<double>() - t0;
        break;
      }
    }
    cut_json.push_back(c);
  }
  const stream::LoaderStats ls = loader ? loader->stats() : stream::LoaderStats{};
  json summary = {{"mode", options->interactive ? "interactive" : "complete"},
                  {"pager", options->radius > 0 ? "radius" : "priority"},
                  {"frames", frames.size()},
                  {"p50_frame_ms", percentile(frame_ms, 0.5)},
                  {"p99_frame_ms", percentile(frame_ms, 0.99)},
                  {"max_frame_ms", percentile(frame_ms, 1.0)},
                  {"p50_cpu_ms", percentile(cpu_ms, 0.5)},
                  {"p99_cpu_ms", percentile(cpu_ms, 0.99)},
                  {"complete", complete},
                  {"bytes_fetched", ls.bytes_fetched},
                  {"final_view_bytes", view_bytes(store, *terrain, last)},
                  {"drawn_bytes", file_bytes(store, drawn)},
                  {"loaded", ls.loaded},
                  {"failed", ls.failed},
                  {"cancelled", ls.cancelled},
                  {"prefetched", ls.prefetched},
                  {"prefetch_used", ls.prefetch_used},
                  {"cuts", cut_json}};
  if (!options->stats.empty()) {
    if (auto st =
            write_json(options->stats, json{{"summary", summary}, {"frames", frames}}.dump(1));
        !st) {
      return report_error(st.error().message);
    }
  }
  if (!options->events.empty()) {
    std::string text;
    for (const json& e : events) text += e.dump() + "\n";
    if (auto st = write_json(options->events, text); !st) return report_error(st.error().message);
  }
  std::printf(
      "%zu frames (%s): frame time p50 %.2f ms, p99 %.2f ms; %s; %llu tiles loaded, "
      "%llu failed, %.1f MB fetched\n",
      frames.size(), options->interactive ? "interactive" : "complete", percentile(frame_ms, 0.5),
      percentile(frame_ms, 0.99), complete ? "last frame complete" : "last frame NOT complete",
      static_cast<unsigned long long>(ls.loaded), static_cast<unsigned long long>(ls.failed),
      static_cast<double>(ls.bytes_fetched) / 1e6);
  return 0;
}

}  // namespace relief::cli
