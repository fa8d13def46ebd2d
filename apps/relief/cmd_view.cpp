// `relief view`: argument parsing and output around the viewer (libs/window).
#include <sys/resource.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <thread>

#include <fmt/format.h>
#include <nlohmann/json.hpp>

#include "allocator.h"
#include "args.h"
#include "commands.h"
#include "output_safety.h"
#include "relief/base/file_io.h"
#include "relief/base/memory_use.h"
#include "relief/base/threads.h"
#include "relief/lod/measured_error.h"
#include "relief/stream/tile_loader.h"
#include "relief/view/path_file.h"
#include "relief/window/viewer.h"
#include "relief/window/window.h"
#include "render_path.h"
#include "render_setup.h"

namespace relief::cli {

namespace {

constexpr const char* kViewHelp =
    R"(usage: relief view STORE [--imagery STORE2] [--camera C | --look-at L] [options]
       relief view STORE --play PATH.json [--exit-when-done] [--stats STATS.json]
       relief view STORE [--elevation-op OP [--elevation-param K=V]...]... [options]

Opens a window (GLFW, OpenGL 4.5 core; Mesa's llvmpipe where there is no GPU)
and flies over an elevation store. Frames never wait for I/O: they draw what
is resident while worker threads load what the view asks for. Without a
display, `relief render` draws stills and camera paths headless.

Keys: Tab or F1 panels, F8 vsync, F9 start/stop recording, F10 export the
recorded path, F11 fullscreen, F12 screenshot (terrain only, PNG), Escape quit;
the control mode takes the rest. A left drag that starts inside a lens's
circle (--lens) moves the lens over the terrain; with Control held, or outside
every lens, it goes to the control mode.

  --camera LON,LAT,HEIGHT,HEADING,PITCH,ROLL   the start (as relief render)
  --look-at LON,LAT,HEIGHT,RANGE,HEADING,PITCH  (default: the whole store)
options:
  --elevation STORE3 another elevation layer, fused with STORE at draw time
                     (repeatable; same tile size and finest level)
  --fuse first|mean  how elevation layers fuse: the first valid sample in the
                     order given (default), or the mean of the valid ones
  --weights W1,W2,...  with --fuse mean: one weight > 0 per elevation layer
                     (STORE first), as relief fuse --weights
  --imagery STORE2   drape an imagery store (a layer the panels switch on and off)
  --size WxH         window size in pixels (default 1024x768)
  --mode M           orbit (default), aircraft, walk or motorbike
  --pixel-error E    largest screen-space error in pixels when still (default 1)
  --no-speed-lod     do not relax the pixel error while the view moves
  --target-fps F     while the view moves and frames take longer than 1/F s,
                     relax the pixel error further, up to 3 times; while they
                     are well within it, relax it less than the speed would,
                     down to --pixel-error (default 30; 0: no budget, only the
                     speed relaxes it; a still view is always drawn at
                     --pixel-error)
  --play PATH.json   play a camera path (the JSON that relief render --path reads)
  --max-frames N     refuse a --play path of more than N frames at its fps
                     (default 100000)
  --exit-when-done   quit once the path has ended (at once without --play) and a
                     frame is complete, or --until-complete seconds later
  --until-complete S (default 30)
  --stats FILE       per-frame statistics and a summary as JSON, written at exit
  --error-points FILE  with --stats: the last frame's screen-space error at
                     these data points, [[LON, LAT, HEIGHT], ...] (bench/web
                     measures another client's frame against the same points)
  --record FILE      record the camera of every frame to a path JSON, written at
                     exit (F9 pauses and resumes)
  --export-movie FILE.mp4  F10 (and the end of an --exit-when-done session)
                     renders the recorded path as this movie, as relief render
                     --path P -o FILE.mp4 does (complete frames, window size)
  --screenshot FILE  write the last frame (terrain only) as PNG at exit
  --screenshot-dir DIR  where F12 writes relief_NNNN.png (default .)
  --no-panels        start with the panels hidden
  --no-overlap       wait for the GL to draw each frame and swap it before the
                     next (by default the next frame is refined while the GL
                     draws this one, and swaps it: docs/viewer.md, "Overlap")
  --no-vsync         do not wait for the display's refresh
  --uploads-per-frame N  a frame uploads at most N elevation tiles new to the
                     GPU; quads needing more wait for the next frames
                     (default %UPLOADS%; 0: no limit)
  --loader-nice N    run the tile loaders N nice levels below the render thread
                     (0-19, default %NICE%: frames first; 0 on a machine shared
                     with work that would starve them; docs/streaming.md)
  --memory-budget SIZE  every tile cache in main memory (default 2GiB), the GPU
                     cache too on a software rasteriser (as relief render)
  --fov, --exaggeration, --lod, --sky, --gpu-budget, --cache, --cache-size
                     as relief render
  --refine-threads N as relief render; by default one per core, but the
                     render thread alone on a software rasteriser (llvmpipe)
                     with overlap: its cores rasterise the previous frame
                     while a frame refines
%TEXTURE%)";

// Elevation tiles a frame of the viewer uploads at most (SceneOptions::
// uploads_per_frame): ~0.2 ms each on llvmpipe with their slopes, and in
// bench/view's flights up to 76 arrived in one frame (docs/viewer.md).
constexpr uint32_t kUploadsPerFrame = 16;

// Nice levels the viewer's loaders run below its render thread unless
// --loader-nice says otherwise: decoding and preparing tiles take the cores
// from the frame (and from llvmpipe's rasteriser) in bursts. On bench/view's
// Himalaya flight at 2 px the p99 frame fell from 63 to 50 ms (48 at nice
// 19, which would leave the loads a background build's leftovers), fps p50
// within the runs' spread (docs/streaming.md, "In flight").
constexpr int kViewerLoaderNice = 10;

// The frame rate the viewer holds while the view moves unless --target-fps
// says otherwise (docs/viewer.md, "Frame budget"). Without it the slowest
// frames of a flight are stretches whose fixed threshold asks for 2-3 times
// the median's triangles: bench/view's flights at 2 px had p99 at 1.79-1.84
// times p50 on 2026-12-07; with it 1.42-1.46. A still view is drawn at --pixel-error
// either way, and a budget met with time to spare tightens the threshold
// back towards it.
constexpr double kDefaultTargetFps = 30;

// An output written at exit must be writable now, not after a long session.
Status check_writable(const char* option, const std::string& path) {
  std::filesystem::path dir = std::filesystem::path(path).parent_path();
  if (dir.empty()) dir = ".";
  std::error_code ec;
  if (!std::filesystem::is_directory(dir, ec)) {
    return fail(fmt::format("{}: {}: {} is not a directory", option, path, dir.string()));
  }
  if (::access(dir.c_str(), W_OK) != 0) {
    return fail(fmt::format("{}: {}: cannot write in {}", option, path, dir.string()));
  }
  return {};
}

Status check_view_outputs(const Args& args, const std::vector<std::string>& texture_paths) {
  std::vector<std::string> inputs = args.positional();
  inputs.insert(inputs.end(), texture_paths.begin(), texture_paths.end());
  for (const char* name : {"--imagery", "--play", "--error-points"}) {
    if (auto p = args.get(name)) inputs.push_back(*p);
  }
  for (const std::string& p : args.get_all("--elevation")) inputs.push_back(p);
  std::vector<Output> outputs;
  if (auto movie = args.get("--export-movie"); movie && !is_movie_output(*movie)) {
    return fail("--export-movie: " + *movie + ": not a movie (FILE.mp4)");
  }
  for (const char* name : {"--stats", "--record", "--screenshot", "--export-movie"}) {
    if (auto p = args.get(name)) {
      RELIEF_CHECK(check_writable(name, *p));
      outputs.push_back({name, *p});
    }
  }
  if (auto p = args.get("--screenshot-dir")) {
    std::error_code ec;
    if (!std::filesystem::is_directory(*p, ec)) {
      return fail("--screenshot-dir: " + *p + " is not a directory");
    }
    outputs.push_back({"--screenshot-dir", *p, OutputKind::Directory});
  }
  return check_outputs_spare_inputs(outputs, inputs);
}

// --error-points FILE: [[lon, lat, height], ...], degrees and metres.
Result<std::vector<lod::DataPoint>> read_error_points(const std::string& path) {
  constexpr uint64_t kMaxBytes = uint64_t{64} << 20;
  const auto bytes = RELIEF_TRY(read_file(path, kMaxBytes));
  const char* text = reinterpret_cast<const char*>(bytes.data());
  const nlohmann::json j = nlohmann::json::parse(text, text + bytes.size(), nullptr, false);
  if (!j.is_array()) return fail("--error-points " + path + ": not a JSON array");
  std::vector<lod::DataPoint> points;
  for (const nlohmann::json& p : j) {
    const bool triple =
        p.is_array() && p.size() == 3 &&
        std::all_of(p.begin(), p.end(), [](const auto& v) { return v.is_number(); });
    const lod::DataPoint d =
        triple ? lod::DataPoint{p[0].get<double>(), p[1].get<double>(), p[2].get<double>()}
               : lod::DataPoint{NAN, NAN, NAN};
    if (!(std::abs(d.lon) <= 180 && std::abs(d.lat) <= 90 && std::isfinite(d.height))) {
      return fail(
          fmt::format("--error-points {}: point {}: expected [lon, lat, height] in degrees "
                      "and metres, got {}",
                      path, points.size(), p.dump()));
    }
    points.push_back(d);
  }
  return points;
}

// The whole store, seen from the south at 45 degrees.
lod::Camera default_camera(const RenderSetup& s) {
  const geo::GeoBox& e = s.has_elevation ? s.store.manifest().extent
                                         : s.textures.layers.front().store->manifest().extent;
  const double range = std::max(e.height(), e.width() * 0.75) * 111e3 * 1.2;
  return lod::look_at(0.5 * (e.west + e.east), 0.5 * (e.south + e.north), 0, range, 0, -45, s.fov,
                      s.width, s.height);
}

Result<window::ViewerOptions> viewer_options(const Args& args, const RenderSetup& setup) {
  window::ViewerOptions o;
  if (auto mode = args.get("--mode")) {
    auto m = view::parse_control_mode(*mode);
    if (!m || *m == view::ControlMode::playback) {
      return fail("--mode: '" + *mode + "' is none of orbit, aircraft, walk, motorbike");
    }
    o.mode = *m;
  }
  if (args.get("--camera") || args.get("--look-at")) {
    o.start = RELIEF_TRY(parse_camera(args, setup));
  } else {
    o.start = default_camera(setup);
    if (auto view = lod::make_view(o.start); !view) {
      return fail(fmt::format("the default camera, over the store's whole extent: {}",
                              view.error().message));
    }
  }
  if (auto play = args.get("--play")) {
    view::PathFile path = RELIEF_TRY(view::read_path_file(
        *play, [&](const std::string& where, const std::vector<double>& values) {
          return camera_from_values(where, values, setup);
        }));
    const int max_frames =
        RELIEF_TRY(args.get_int("--max-frames", 1, 100000000)).value_or(view::kDefaultMaxFrames);
    RELIEF_TRY(view::count_path_frames(path.keyframes, path.fps, max_frames, *play));
    o.mode = view::ControlMode::playback;
    o.start = path.keyframes.front().camera;
    o.controller.path = std::move(path.keyframes);
    o.record_fps = path.fps;
  }
  o.speed_lod.enabled = !args.has("--no-speed-lod");
  double target_fps = kDefaultTargetFps;
  if (auto fps = RELIEF_TRY(args.get_double("--target-fps"))) {
    if (!(*fps >= 0 && *fps <= 1000)) return fail("--target-fps: must be in [0, 1000]");
    target_fps = *fps;
  }
  o.frame_budget.target_ms = target_fps > 0 ? 1e3 / target_fps : 0;
  o.exit_when_done = args.has("--exit-when-done");
  if (auto s = RELIEF_TRY(args.get_double("--until-complete"))) {
    if (!(*s >= 0 && *s <= 3600)) return fail("--until-complete: must be in [0, 3600] s");
    o.until_complete = *s;
  }
  o.record = args.get("--record").has_value();
  o.screenshot_dir = args.get("--screenshot-dir").value_or(".");
  o.panels = !args.has("--no-panels");
  o.overlap = !args.has("--no-overlap");
  o.refine_threads_auto = !setup.refine_threads;
  o.collect_frames = args.get("--stats").has_value();
  return o;
}

// What the loaders' settings did, as the kernel and the loader saw it: the
// nice value of every loader worker and of the render thread (this one),
// and the most workers that prepared tiles at once.
nlohmann::json loaders_json(view::Scene& scene, const view::SceneOptions& so) {
  nlohmann::json nice = nlohmann::json::array();
  for (const ThreadInfo& t : threads_named("relief-loader")) nice.push_back(t.nice);
  errno = 0;
  const int own = getpriority(PRIO_PROCESS, static_cast<id_t>(gettid()));
  nlohmann::json j = {{"worker_nice", nice},
                      {"render_thread_nice", errno ? 0 : own},
                      {"max_preparing", so.loader.max_preparing}};
  if (stream::TileLoader* loader = scene.elevation_loader()) {
    j["most_preparing"] = loader->stats().most_preparing;
  }
  return j;
}

// The frame budget's rate at the start of the session, as given (the budget
// keeps a period: 1e3 / (1e3 / 30) is not 30 in floating point).
double target_fps(const window::ViewerOptions& viewer) {
  const double ms = viewer.frame_budget.target_ms;
  return ms > 0 ? std::round(1e9 / ms) / 1e6 : 0.0;
}

// `scene`: the scene's options (refine_threads 0: one per core).
nlohmann::json stats_json(const window::ViewerSummary& s, const std::string& renderer,
                          nlohmann::json loaders, const view::SceneOptions& scene,
                          const window::ViewerOptions& viewer) {
  const unsigned refine_threads = scene.refine_threads;
  nlohmann::json frames = nlohmann::json::array();
  for (const window::ViewerFrame& f : s.frames_list) {
    const lod::Camera& c = f.camera;
    frames.push_back({{"frame", f.index},
                      {"time", f.time},
                      {"frame_ms", f.frame_ms},
                      {"draw_ms", f.draw_ms},
                      {"select_ms", f.select_ms},
                      {"prepare_ms", f.prepare_ms},
                      {"gpu_ms", f.gpu_ms},
                      {"submit_ms", f.submit_ms},
                      {"swap_ms", f.swap_ms},
                      {"present_ms", f.present_ms},
                      {"tiles_uploaded", f.tiles_uploaded},
                      {"uploads_deferred", f.uploads_deferred},
                      {"page_faults", f.page_faults},
                      {"cached_bytes", f.cached_bytes},
                      {"pixel_error", f.pixel_error},
                      {"speed_factor", f.speed_factor},
                      {"budget_factor", f.budget_factor},
                      {"camera", {c.lon, c.lat, c.height, c.heading, c.pitch, c.roll}},
                      {"quads", f.quads},
                      {"triangles", f.triangles},
                      {"triangles_per_pixel", f.triangles_per_pixel},
                      {"uploaded_bytes", f.uploaded_bytes},
                      {"complete", f.complete},
                      {"refine",
                       {{"ms", f.refine_ms},
                        {"cpu_ms", f.refine_cpu_ms},
                        {"marks_evaluated", f.marks_evaluated},
                        {"criteria_ms", f.criteria_ms},
                        {"marks_near", f.marks_near},
                        {"marks_reused", f.marks_reused},
                        {"quads_reused", f.quads_reused},
                        {"tiles_measured", f.tiles_measured}}},
                      {"process_cpu_ms", f.process_cpu_ms}});
  }
  auto fps = [](double ms) { return ms > 0 ? 1e3 / ms : 0.0; };
  nlohmann::json summary = {
      {"frames", s.frames},
      {"skipped_frames", s.skipped_frames},
      {"seconds", s.seconds},
      {"fps_p50", fps(s.p50_frame_ms)},
      {"fps_p99", fps(s.p99_frame_ms)},  // the fps of the p99 frame time
      {"p50_frame_ms", s.p50_frame_ms},
      {"p99_frame_ms", s.p99_frame_ms},
      {"complete", s.complete},
      {"path_finished", s.path_finished},
      {"path_end", s.path_end ? nlohmann::json(*s.path_end) : nlohmann::json()},
      {"renderer", renderer},
      {"allocator", allocator_description()},
      {"refine_threads", refine_threads ? refine_threads : std::thread::hardware_concurrency()},
      {"uploads_per_frame", scene.uploads_per_frame},
      {"memory_budget_bytes", scene.memory_budget},
      {"peak_rss_bytes", peak_resident_set_bytes()},
      {"target_fps", target_fps(viewer)},
      {"loaders", std::move(loaders)}};
  return {{"summary", summary}, {"frames", frames}};
}

// "Export recorded path": the path to --record FILE (else the next free
// relief_path_NNNN.json in --screenshot-dir) and, with --export-movie, the
// movie rendered by the code of `relief render --path P -o MOVIE.mp4`. Runs
// on the viewer's export thread (render_path makes its own headless context).
Status export_recorded_path(const Args& args, RenderSetup& setup, const view::PathFile& path) {
  std::filesystem::path file;
  if (auto record = args.get("--record")) {
    file = *record;
  } else {
    const std::filesystem::path dir = args.get("--screenshot-dir").value_or(".");
    for (int n = 0; file.empty() || std::filesystem::exists(file); ++n) {
      file = dir / fmt::format("relief_path_{:04d}.json", n);
    }
  }
  RELIEF_CHECK(view::write_path_file(file.string(), path));
  std::fprintf(stderr, "relief: wrote the recorded path to %s\n", file.c_str());
  auto movie = args.get("--export-movie");
  if (!movie) return {};
  // The store too: a remote one is exported with the path prefetched.
  std::vector<std::string> argv = {"--path", file.string(), "-o", *movie};
  if (!args.positional().empty()) argv.insert(argv.begin(), args.positional()[0]);
  auto render_args = Args::parse(argv, {{"--path"}, {"--output", "-o"}}, "view");
  if (!render_args) return std::unexpected(render_args.error());
  if (render_path(*render_args, setup) != 0) {  // its error is on stderr
    return fail("--export-movie: " + *movie + ": the export failed");
  }
  return {};
}

int view_session(const Args& args, RenderSetup& setup) {
  auto options = viewer_options(args, setup);
  if (!options) return report_error(options.error().message);
  std::vector<lod::DataPoint> error_points;
  if (auto path = args.get("--error-points")) {
    if (!args.get("--stats")) return report_error("--error-points: needs --stats (its output)");
    auto points = read_error_points(*path);
    if (!points) return report_error(points.error().message);
    error_points = std::move(*points);
  }
  // Refused now, not after the session it would have ended.
  if (auto movie = args.get("--export-movie"); movie && (setup.width % 2 || setup.height % 2)) {
    return report_error(fmt::format(
        "--export-movie {}: the window is {}x{}; a movie needs an even width and height", *movie,
        setup.width, setup.height));
  }
  options->export_path = [&args, &setup](const view::PathFile& path) {
    return export_recorded_path(args, setup, path);
  };
  view::SceneOptions so = scene_options(setup);
  so.interactive = true;
  // The render thread keeps a core while tiles are prepared (docs/streaming.md).
  so.loader.max_preparing = std::max(1, static_cast<int>(std::thread::hardware_concurrency()) - 1);
  so.lookahead_frames = 15;  // half a second ahead at 30 fps
  so.on_growth_ahead = prefault_in_background;
  so.uploads_per_frame = kUploadsPerFrame;
  auto uploads = args.get_int("--uploads-per-frame", 0, 1 << 20);
  if (!uploads) return report_error(uploads.error().message);
  if (*uploads) so.uploads_per_frame = static_cast<uint32_t>(**uploads);

  window::WindowOptions wo;
  wo.width = setup.width;
  wo.height = setup.height;
  wo.title = "relief: " +
             (args.positional().empty() ? setup.textures.paths.front() : args.positional()[0]);
  wo.vsync = !args.has("--no-vsync");
  auto window = window::Window::create(wo);
  if (!window) return report_error(window.error().message);
  auto viewer = window::Viewer::create(**window, setup.has_elevation ? &setup.store : nullptr,
                                       setup.imagery ? &*setup.imagery : nullptr, so, *options,
                                       steady_clock());
  if (!viewer) return report_error(viewer.error().message);
  auto summary = (*viewer)->run();
  if (!summary) return report_error(summary.error().message);
  Status exported = (*viewer)->wait_for_export();  // an F10 export still running
  // A scripted session with --export-movie exports what it recorded.
  if (exported && args.get("--export-movie") && options->exit_when_done) {
    if (!(*viewer)->export_recorded()) {
      return report_error("--export-movie: nothing was recorded (--record FILE records)");
    }
    exported = (*viewer)->wait_for_export();
  }
  if (!exported) return report_error(exported.error().message);

  if (auto path = args.get("--screenshot")) {
    if (auto st = (*viewer)->screenshot(*path); !st) return report_error(st.error().message);
  }
  if (auto path = args.get("--record")) {
    if (summary->recorded.empty()) return report_error("--record: no frame was recorded");
    view::PathFile file{options->record_fps, summary->recorded};
    if (auto st = view::write_path_file(*path, file); !st) {
      return report_error(st.error().message);
    }
  }
  if (auto path = args.get("--stats")) {
    nlohmann::json stats =
        stats_json(*summary, (*window)->renderer(), loaders_json((*viewer)->scene(), so),
                   (*viewer)->scene().options(), *options);
    if (args.get("--error-points") && !summary->frames_list.empty()) {
      // The last frame's mesh against the given data, in pixels (null: not
      // drawn there, or off screen).
      auto pixels = (*viewer)->scene().measure_last_frame_at(summary->frames_list.back().camera,
                                                             error_points);
      if (!pixels) return report_error(pixels.error().message);
      nlohmann::json list = nlohmann::json::array();
      for (const std::optional<double>& p : *pixels)
        list.push_back(p ? nlohmann::json(*p) : nullptr);
      stats["summary"]["final_error"] = {{"points", error_points.size()}, {"pixels", list}};
    }
    const std::string text = stats.dump(1);
    if (auto st = write_json(*path, text); !st) return report_error(st.error().message);
  }
  std::printf("%zu frames in %.1f s: frame time p50 %.1f ms, p99 %.1f ms; last frame %s\n",
              summary->frames, summary->seconds, summary->p50_frame_ms, summary->p99_frame_ms,
              summary->complete ? "complete" : "NOT complete");
  // A session that went without some tiles did not show the store: each is
  // named, and the exit status says so (as `relief render` fails on one).
  for (const std::string& error : summary->unreadable_tiles) report_error(error);
  return summary->unreadable_tiles.empty() ? 0 : 1;
}

}  // namespace

int run_view(const std::vector<std::string>& command_line) {
  if (wants_help(command_line)) {
    std::string help = help_with_layer_options(kViewHelp);
    help.replace(help.find("%UPLOADS%"), 9, std::to_string(kUploadsPerFrame));
    help.replace(help.find("%NICE%"), 6, std::to_string(kViewerLoaderNice));
    return print_help(help.c_str());
  }
  // Layer options repeat and their order matters: taken out first.
  std::vector<std::string> argv = command_line;
  auto layers = take_layer_options(argv);
  if (!layers) return report_error(layers.error().message);
  auto args = Args::parse(argv,
                          with_scene_options({{"--mode"},
                                              {"--no-speed-lod", "", false},
                                              {"--target-fps"},
                                              {"--play"},
                                              {"--max-frames"},
                                              {"--exit-when-done", "", false},
                                              {"--until-complete"},
                                              {"--stats"},
                                              {"--error-points"},
                                              {"--record"},
                                              {"--screenshot"},
                                              {"--screenshot-dir"},
                                              {"--export-movie"},
                                              {"--no-panels", "", false},
                                              {"--no-overlap", "", false},
                                              {"--no-vsync", "", false},
                                              {"--uploads-per-frame"}}),
                          "view");
  if (!args) return report_error(args.error().message);
  if (args->get("--camera") && args->get("--look-at")) {
    return report_error("view: give at most one of --camera and --look-at");
  }
  if (args->get("--play") &&
      (args->get("--camera") || args->get("--look-at") || args->get("--mode"))) {
    return report_error("view: --play replaces --camera, --look-at and --mode");
  }
  if (auto safe = check_view_outputs(*args, layers->textures.paths); !safe) {
    return report_error(safe.error().message);
  }
  auto setup = parse_render_setup(*args, std::move(layers->textures), std::move(layers->elevation));
  if (!setup) return report_error(setup.error().message);
  if (!args->get("--loader-nice")) setup->loader_nice = kViewerLoaderNice;
  keep_freed_memory();
  prefault_frame_heap(kFrameHeapBytes);
  return view_session(*args, *setup);
}

}  // namespace relief::cli
