#include "render_path.h"

#include <algorithm>
#include <cctype>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <memory>
#include <optional>

#include <fmt/format.h>
#include <nlohmann/json.hpp>

#include "allocator.h"
#include "commands.h"
#include "relief/base/file_io.h"
#include "relief/base/memory_use.h"
#include "relief/base/progress.h"
#include "relief/base/units.h"
#include "relief/lod/camera_path.h"
#include "relief/video/video_writer.h"
#include "relief/view/path_file.h"
#include "relief/view/path_player.h"

namespace relief::cli {

namespace {

using nlohmann::json;

struct PathOptions {
  bool interactive = true;
  double fps = 0;  // 0: the path's
  stream::LoaderOptions loader;
  bool prefetch = true;
  double radius = 0;  // > 0: the radius pager
  double until_complete = 0;
  int max_frames = view::kDefaultMaxFrames;
  std::string events, stats;
  // --error-samples: finest samples whose projected error each frame's
  // statistics measure (0: none).
  int error_samples = 500;
  bool frames = true;
  bool movie = false;  // -o *.mp4: complete frames encoded into one file
  video::VideoOptions video;
};

Result<PathOptions> parse_path_options(const Args& args) {
  PathOptions o;
  if (auto mode = args.get("--mode")) {
    if (*mode != "interactive" && *mode != "complete") {
      return fail("--mode: '" + *mode + "' is neither interactive nor complete");
    }
    o.interactive = *mode == "interactive";
  }
  if (auto fps = RELIEF_TRY(args.get_double("--fps"))) {
    if (!(*fps >= view::kMinPathFps && *fps <= view::kMaxPathFps)) {
      return fail(
          fmt::format("--fps: must be in [{:g}, {:g}]", view::kMinPathFps, view::kMaxPathFps));
    }
    o.fps = *fps;
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
  if (auto n = RELIEF_TRY(error_samples(args))) o.error_samples = *n;
  o.frames = !args.has("--no-frames");
  o.movie = is_movie_output(*args.get("--output"));
  if (!o.movie) {
    for (const char* name : {"--codec", "--crf", "--preset"}) {
      if (args.get(name)) return fail(fmt::format("{}: only for a movie (-o FILE.mp4)", name));
    }
    return o;
  }
  if (o.interactive && args.get("--mode")) {
    return fail("--mode interactive: a movie (-o *.mp4) is made of complete frames");
  }
  if (!o.frames) return fail("--no-frames: a movie (-o *.mp4) is its frames");
  o.interactive = false;
  o.video.codec = args.get("--codec").value_or(o.video.codec);
  if (auto crf = RELIEF_TRY(args.get_int("--crf", 0, 51))) o.video.crf = *crf;
  o.video.preset = args.get("--preset").value_or(o.video.preset);
  RELIEF_CHECK(video::check_options(o.video));
  return o;
}

json refine_json(const view::FrameReport& r) {
  const lod::RefineStats& s = *r.refine;
  return {{"ms", s.seconds * 1e3},
          {"cpu_ms", s.cpu_seconds * 1e3},
          {"marks_evaluated", s.marks_evaluated},
          {"criteria_ms", s.criteria_seconds * 1e3},
          {"marks_near", s.marks_near},
          {"marks_reused", s.marks_reused},
          {"quads_reused", s.quads_reused},
          {"tiles_measured", s.tiles_measured},
          {"tiles_prepared", s.tiles_prepared},
          {"tiles_cached", r.refine_cache_tiles},
          {"cache_bytes", r.refine_cache_bytes},
          {"too_coarse_quads", s.too_coarse},
          {"unresolved_diamonds", s.unresolved}};
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

// Whether tiles come over a network (a URL store, or a simulated link).
bool fetched_over_a_link(const Args& args) {
  const std::string& store = args.positional().empty() ? std::string() : args.positional()[0];
  return store.starts_with("http://") || store.starts_with("https://") ||
         args.get("--simulate-latency") || args.get("--simulate-bandwidth");
}

}  // namespace

bool is_movie_output(const std::string& output) {
  std::string extension = std::filesystem::path(output).extension().string();
  std::ranges::transform(extension, extension.begin(),
                         [](unsigned char c) { return static_cast<char>(std::tolower(c)); });
  return extension == ".mp4";
}

int render_path(const Args& args, RenderSetup& setup, const Clock& clock) {
  auto options = parse_path_options(args);
  if (!options) return report_error(options.error().message);
  if (setup.full_resolution) return report_error("--full-resolution: for stills only, not --path");
  auto path = view::read_path_file(
      *args.get("--path"), [&](const std::string& where, const std::vector<double>& values) {
        return camera_from_values(where, values, setup);
      });
  if (!path) return report_error(path.error().message);
  const std::vector<lod::Keyframe>& keys = path->keyframes;
  const double path_fps = path->fps;
  const double fps = options->fps > 0 ? options->fps : path_fps;
  const auto counted = view::count_path_frames(keys, fps, options->max_frames, *args.get("--path"));
  if (!counted) return report_error(counted.error().message);
  const size_t path_frames = *counted;
  const std::string out = *args.get("--output");
  std::unique_ptr<video::VideoWriter> movie;
  if (options->movie) {  // created first: an unwritable movie fails before any frame
    if (setup.width % 2 || setup.height % 2) {
      return report_error(fmt::format("--size: {}x{}: a movie needs an even width and height",
                                      setup.width, setup.height));
    }
    auto writer = video::VideoWriter::open(out, setup.width, setup.height, fps, options->video);
    if (!writer) return report_error(writer.error().message);
    movie = std::move(*writer);
  } else if (options->frames) {
    std::error_code ec;
    std::filesystem::create_directories(out, ec);
    if (ec) return report_error(out + ": cannot create the frame directory: " + ec.message());
  }

  view::SceneOptions so = scene_options(setup);
  so.on_growth_ahead = prefault_in_background;
  // A movie of a remote store (or a simulated link): complete frames from an
  // interactive scene that waits for each frame's tiles while the path ahead
  // is prefetched on the loaders' threads (PathOptions::wait_complete), so
  // fetches overlap rendering. Not for a local store: read from the page
  // cache, its tiles are cheaper to read when a frame needs them than to
  // prepare on load (~25 % more CPU time measured, on 2 cores). Also not
  // with --no-prefetch.
  const bool wait_complete = options->movie && options->prefetch && fetched_over_a_link(args);
  so.interactive = options->interactive || wait_complete;
  so.loader = options->loader;  // its memory budget is a share of so.memory_budget
  so.loader.worker_nice = setup.loader_nice;
  so.prefetch = options->prefetch;
  so.lookahead_frames = 0.5 * fps;  // prefetch half a second ahead
  so.radius_tiles = options->radius;
  auto context = render::GlContext::create_headless();
  if (!context) return report_error(context.error().message);
  auto target = render::make_offscreen_target(setup.width, setup.height);
  if (!target) return report_error(target.error().message);
  auto scene = view::Scene::create(elevation_of(setup), setup.imagery ? &*setup.imagery : nullptr,
                                   so, clock);
  if (!scene) return report_error(scene.error().message);
  stream::TileLoader* loader = (*scene)->elevation_loader();
  stream::TileLoader* imagery_loader = (*scene)->imagery_loader();
  lod::TerrainModel& terrain = (*scene)->terrain();

  json events = json::array();
  size_t frame_index = 0;
  if (loader && !options->events.empty()) {
    loader->subscribe([&](const stream::TileEvent& e) {
      events.push_back({{"frame", frame_index},
                        {"event", stream::to_string(e.kind)},
                        {"tile", e.key.to_string()},
                        {"bytes", e.bytes},
                        {"prefetch", e.prefetch},
                        {"error", e.error}});
    });
  }
  json frames = json::array();
  std::unique_ptr<Progress> progress = make_progress_for_stderr();
  progress->begin(options->movie ? "movie" : "frames", path_frames);
  view::PathCallbacks callbacks;
  callbacks.frame_start = [&](size_t i) { frame_index = i; };
  callbacks.frame_done = [&](const view::FrameRecord& r) -> Status {
    const lod::Camera& camera = r.report.camera;
    const render::FrameStats& frame = r.report.draw;
    json f = {
        {"frame", r.index},
        {"time", r.time},
        {"camera",
         {camera.lon, camera.lat, camera.height, camera.heading, camera.pitch, camera.roll}},
        {"frame_ms", r.report.frame_seconds * 1e3},
        {"cpu_ms", r.report.cpu_seconds * 1e3},
        {"page_faults", r.report.page_faults},
        {"selection_ms", r.report.selection.seconds * 1e3},
        {"draw_ms", (frame.prepare_seconds + frame.gpu_seconds) * 1e3},
        {"gpu_ms", frame.gpu_seconds * 1e3},
        {"quads", r.report.selection.quads},
        {"triangles", frame.triangles},
        {"triangles_per_pixel", frame.triangles_per_pixel()},
        {"draw_calls", frame.draw_calls},
        {"uploaded_bytes", {{"geometry", frame.geometry_bytes}, {"textures", frame.texture_bytes}}},
        {"waiting_quads", r.report.selection.waiting},
        {"complete", r.report.complete},
        {"gpu",
         {{"textures", frame.gpu_textures},
          {"bytes", frame.gpu_bytes},
          {"budget_bytes", frame.gpu_budget},
          {"slots", frame.gpu_slots},
          {"allocated_bytes", frame.gpu_allocated_bytes},
          {"uploads", frame.uploads},
          {"evicted", frame.gpu_evicted}}},
        {"rss_bytes", resident_set_bytes()},
        {"cached_bytes", r.report.cached_bytes},
        {"memory_budget_bytes", setup.memory_budget},
        {"exact_errors",
         {{"measured", terrain.error_counts().measured},
          {"prepared", terrain.error_counts().prepared}}}};
    if (r.report.refine) f["refine"] = refine_json(r.report);
    // Measured, not the bound: a lower bound of the true maximum.
    if (!options->stats.empty() && options->error_samples > 0) {
      const lod::MeasuredError e =
          RELIEF_TRY((*scene)->measure_last_frame(camera, options->error_samples));
      f["measured_error"] = {{"max_pixels", e.max_pixels}, {"samples", e.samples}};
    }
    if (loader) f["memory"] = loader_json(loader->stats());
    if (setup.disk_cache) {
      const net::DiskCacheStats d = setup.disk_cache->stats();
      f["disk_cache"] = {{"bytes", d.bytes},         {"budget_bytes", setup.disk_cache_budget},
                         {"hits", d.hits},           {"misses", d.misses},
                         {"evictions", d.evictions}, {"shared", d.shared},
                         {"repaired", d.repaired}};
    }
    if (imagery_loader) f["imagery_memory"] = loader_json(imagery_loader->stats());
    if (!setup.textures.layers.empty()) {
      f["texture_layers"] = {{"tiles_processed", frame.layer_tiles_processed},
                             {"processing_ms", frame.processing_seconds * 1e3},
                             {"misses", frame.texture_misses}};
    }
    frames.push_back(std::move(f));
    progress->advance();
    if (!options->frames) return {};
    if (movie) {  // encoded while the next frame renders; rows flipped by the encoder
      std::vector<uint8_t> pixels = movie->take_buffer();
      RELIEF_CHECK((*target)->read_rgba_bottom_up(pixels));
      return movie->write(std::move(pixels), video::RowOrder::bottom_first);
    }
    std::vector<uint8_t> pixels = RELIEF_TRY((*target)->read_rgba());
    const std::string file =
        (std::filesystem::path(out) / fmt::format("frame_{:05d}.png", r.index)).string();
    return write_png(file, pixels, setup.width, setup.height);
  };
  view::PathOptions po;
  po.fps = fps;
  po.until_complete = options->until_complete;
  po.wait_complete = wait_complete;
  auto played = view::play_path(**scene, keys, path_frames, po, **target, clock, callbacks);
  progress->end();
  if (!played) return report_error(played.error().message);
  const view::PathSummary& p = *played;
  std::optional<video::VideoStats> movie_stats;
  if (movie) {
    auto finished = movie->finish();
    if (!finished) return report_error(finished.error().message);
    movie_stats = *finished;
  }

  json cut_json = json::array();
  for (const view::CutReport& c : p.cuts) {
    json j = {{"frame", c.frame}, {"complete_after_s", nullptr}};
    if (c.complete_after_s) j["complete_after_s"] = *c.complete_after_s;
    cut_json.push_back(j);
  }
  const stream::LoaderStats ls = loader ? loader->stats() : stream::LoaderStats{};
  json summary = {{"mode", options->interactive ? "interactive" : "complete"},
                  {"pager", options->radius > 0 ? "radius" : "priority"},
                  {"frames", p.frames},
                  {"p50_frame_ms", p.p50_frame_ms},
                  {"p99_frame_ms", p.p99_frame_ms},
                  {"max_frame_ms", p.max_frame_ms},
                  {"p50_cpu_ms", p.p50_cpu_ms},
                  {"p99_cpu_ms", p.p99_cpu_ms},
                  {"complete", p.complete},
                  {"bytes_fetched", ls.bytes_fetched},
                  {"final_view_bytes", p.final_view_bytes},
                  {"drawn_bytes", p.drawn_bytes},
                  {"loaded", ls.loaded},
                  {"failed", ls.failed},
                  {"cancelled", ls.cancelled},
                  {"prefetched", ls.prefetched},
                  {"prefetch_used", ls.prefetch_used},
                  {"cuts", cut_json},
                  {"allocator", allocator_description()}};
  if (movie_stats) {
    summary["movie"] = {{"file", out},
                        {"codec", options->video.codec},
                        {"crf", options->video.crf},
                        {"preset", options->video.preset},
                        {"frames", movie_stats->frames},
                        {"bytes", movie_stats->bytes},
                        {"encode_ms", movie_stats->encode_seconds * 1e3},
                        {"write_wait_ms", movie_stats->write_wait_seconds * 1e3}};
  }
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
      p.frames, options->interactive ? "interactive" : "complete", p.p50_frame_ms, p.p99_frame_ms,
      p.complete ? "last frame complete" : "last frame NOT complete",
      static_cast<unsigned long long>(ls.loaded), static_cast<unsigned long long>(ls.failed),
      static_cast<double>(ls.bytes_fetched) / 1e6);
  if (movie_stats) {
    std::printf("wrote %s: %llu frames, %dx%d at %g fps, %.1f MB, %s crf %d preset %s\n",
                out.c_str(), static_cast<unsigned long long>(movie_stats->frames), setup.width,
                setup.height, fps, static_cast<double>(movie_stats->bytes) / 1e6,
                options->video.codec.c_str(), options->video.crf, options->video.preset.c_str());
  }
  return 0;
}

}  // namespace relief::cli
