#include <cstdio>

#include <fmt/format.h>
#include <nlohmann/json.hpp>

#include "allocator.h"
#include "args.h"
#include "commands.h"
#include "output_safety.h"
#include "relief/lod/selection.h"
#include "relief/render/terrain_renderer.h"
#include "render_parallel.h"
#include "render_path.h"
#include "render_setup.h"

namespace relief::cli {

namespace {
constexpr const char* kRenderHelp =
    R"(usage: relief render STORE [--imagery STORE2] (--camera C | --look-at L) -o FRAME.png [options]
       relief render STORE [--imagery STORE2] --path PATH.json -o DIR [options]
       relief render STORE [--imagery STORE2] --path PATH.json -o MOVIE.mp4 [options]
       relief render [STORE] --texture STORE2 [--texture-op OP [--texture-param K=V]...]...
                     [--texture-range MIN,MAX] [--texture-opacity A] [--texture-colormap NAME]
                     ... (--camera C | --look-at L | --path PATH.json) -o OUT [options]
       relief render STORE [--elevation STORE3]... --elevation-op OP [--elevation-param K=V]...
                     [--elevation-lens LON,LAT,RADIUS_M [--elevation-lens-op OP ...]...]
                     ... -o OUT [options]

Renders an elevation store headless (EGL; Mesa's llvmpipe where there is no
GPU). The mesh keeps every finest sample within --pixel-error pixels of
where the data puts it on screen: --lod quads splits quads while their mesh's
error bound projects over it; --lod edge-marks (the default) splits quads
only while their level's own error projects over half of it and refines each
quad's triangles by edge marks to the threshold (seed 003 ch. 3), about ten
times fewer triangles.

A still is a complete frame: every quad the view needs at that level of
detail is loaded before drawing. A path (--path) is rendered frame by frame,
by default in interactive mode: frames are drawn at once with what is
resident while worker threads load what the view asks for, nearest the
screen centre first, coarse before fine; --mode complete waits instead.
With -o MOVIE.mp4 the frames are complete and encoded into an H.264 MP4
(docs/video.md) while the next ones render; the file appears only once whole.

  --camera LON,LAT,HEIGHT,HEADING,PITCH,ROLL
                     eye position (degrees, metres above the WGS84 ellipsoid) and
                     orientation (degrees: heading clockwise from north, pitch < 0 looks down)
  --look-at LON,LAT,HEIGHT,RANGE,HEADING,PITCH
                     look at a point from RANGE metres away
  --path PATH.json   camera keyframes: {"fps": 30, "keyframes": [{"time": 0,
                     "camera": [LON,LAT,HEIGHT,HEADING,PITCH,ROLL], "cut": false}, ...]}
                     (a "cut" keyframe is jumped to, not flown to)
options:
  -o, --output PATH  PNG to write (a still), or directory for frame_NNNNN.png (a path),
                     or MOVIE.mp4 (a path as a movie)
  --elevation STORE3 another elevation layer, fused with STORE at draw time
                     (repeatable; same tile size and finest level)
  --fuse first|mean  how elevation layers fuse: the first valid sample in the
                     order given (default), or the mean of the valid ones
  --weights W1,W2,...  with --fuse mean: one weight > 0 per elevation layer
                     (STORE first), as relief fuse --weights
  --imagery STORE2   drape an imagery store; otherwise hypsometric colours with hillshade
  --size WxH         image size in pixels (default 1024x768)
  --fov DEG          vertical field of view (default 60)
  --pixel-error E    largest screen-space error in pixels (default 1)
  --exaggeration X   vertical exaggeration (default 1)
  --lod MODE         edge-marks (default), edge-marks-bottom-up (the same mesh,
                     every mark decided: a reference), edge-marks-gl (every
                     split criterion evaluated by a GL compute shader first:
                     the same mesh; docs/refinement.md) or quads
  --mesh-level R     --lod quads: 2^(R+1) x 2^R squares per quad (default 4)
  --full-resolution  every finest sample a vertex (the brute-force reference)
  --sky R,G,B        background colour, 0-255 (default 156,189,224)
  --stats FILE       statistics as JSON (a path: per frame, and a summary)
  --error-samples N  with --stats: random finest samples whose projected
                     distance to the drawn mesh is measured (default 20000
                     for a still, 500 per frame of a path, ~45 ms a frame
                     over the Pyrenees; 0: not measured)
  --memory-budget SIZE  every tile cache in main memory (default 2GiB): decoded
                     tiles, their diamond errors, imagery, and on a software
                     rasteriser (llvmpipe) the GPU texture cache (L3) too
  --gpu-budget SIZE  GPU texture cache (L3) budget (default 1GiB on a GPU; on a
                     software rasteriser a share of --memory-budget unless given)
  --cache DIR        for a store given as http:// URL(s): keep fetched files under DIR
  --cache-size SIZE  budget of that disk cache (L1, default 1GiB; a file larger than
                     it is not kept: 0 keeps nothing)
  --loader-nice N    run the tile loaders N nice levels below the render thread
                     (0-19, default 0; docs/streaming.md "In flight")
  --refine-threads N threads that refine a frame's edge marks (the same mesh;
                     0, the default: one per core; 1: the render thread only)
  --simulate-latency MS    add MS milliseconds to every store request
  --simulate-bandwidth MBIT  share MBIT Mbit/s among all store requests
path options:
  --mode M           interactive (default) or complete
  --fps N            frames per second (default: the path's, else 30)
  --loads N          loads in flight (default 8)
  --no-prefetch      do not load ahead along the camera's motion
  --pager P          priority (default) or radius:K (every tile within K tile
                     sizes of the camera, level by level; a baseline for benchmarks)
  --until-complete S after the path, keep drawing its last view until complete (at most S s)
  --max-frames N     refuse a path of more than N frames (default 100000)
  --events FILE      every tile lifecycle event as JSON lines
  --no-frames        do not write frame images (statistics only)
movie options (-o MOVIE.mp4):
  --codec C          h264 (default; libx264, yuv420p: even --size only)
  --crf N            quality, 0 (lossless) to 51 (default 18; lower is better)
  --preset P         x264's speed for size: ultrafast .. veryslow (default veryfast)
%TEXTURE%parallel (under mpirun -n N; docs/parallel.md):
  --parallel MODE    sort-first:h|v|grid (screen tiles), sort-last:block|quadtree|active
                     (quads, depth-composited) or wall:WALL.json (one display per rank,
                     written as OUT_rR_cC.png); stills and --path, complete frames
  --composite C      sort-last's depth compositing: radix-k (default, rounds of at most 8
                     ranks), radix-k:K, binary-swap or direct-send
  --parallel-timeout S  a rank that has not answered within S s fails the run (default 60)
)";

// What a render reads and writes, for the check that no output replaces an input.
Status check_render_outputs(const Args& args, const std::vector<std::string>& texture_paths) {
  std::vector<std::string> inputs = args.positional();
  inputs.insert(inputs.end(), texture_paths.begin(), texture_paths.end());
  for (const char* name : {"--imagery", "--path"}) {
    if (auto p = args.get(name)) inputs.push_back(*p);
  }
  for (const std::string& p : args.get_all("--elevation")) inputs.push_back(p);
  const bool frames = args.get("--path") && !is_movie_output(*args.get("--output"));
  std::vector<Output> outputs = {
      {"-o", *args.get("--output"), frames ? OutputKind::Directory : OutputKind::File}};
  for (const char* name : {"--stats", "--events"}) {
    if (auto p = args.get(name)) outputs.push_back({name, *p});
  }
  if (auto p = args.get("--cache")) outputs.push_back({"--cache", *p, OutputKind::Directory});
  return check_outputs_spare_inputs(outputs, inputs);
}

nlohmann::json stats_json(const lod::Selection& s, const render::FrameStats& f) {
  nlohmann::json levels = nlohmann::json::object();
  for (size_t l = 0; l < s.stats.quads_per_level.size(); ++l) {
    if (s.stats.quads_per_level[l]) levels[std::to_string(l)] = s.stats.quads_per_level[l];
  }
  return {{"quads", s.stats.quads},
          {"quads_per_level", levels},
          {"triangles", f.triangles},
          {"triangles_per_pixel", f.triangles_per_pixel()},
          {"draw_calls", f.draw_calls},
          {"uploaded_bytes", {{"geometry", f.geometry_bytes}, {"textures", f.texture_bytes}}},
          {"gpu",
           {{"textures", f.gpu_textures},
            {"bytes", f.gpu_bytes},
            {"slots", f.gpu_slots},
            {"allocated_bytes", f.gpu_allocated_bytes},
            {"budget_bytes", f.gpu_budget}}},
          {"culled_quads", s.stats.culled},
          {"selection_ms", s.stats.seconds * 1e3},
          {"prepare_ms", f.prepare_seconds * 1e3},
          {"gpu_ms", f.gpu_seconds * 1e3},
          {"max_error_pixels", s.stats.max_error_pixels},
          {"texture_layers",
           {{"tiles_processed", f.layer_tiles_processed},
            {"processing_ms", f.processing_seconds * 1e3},
            {"misses", f.texture_misses}}}};
}

int render_still(const Args& args, RenderSetup& setup) {
  if (!args.get("--camera") == !args.get("--look-at")) {
    return report_error("render: give exactly one of --camera and --look-at");
  }
  auto camera = parse_camera(args, setup);
  if (!camera) return report_error(camera.error().message);
  auto samples = error_samples(args);  // checked before anything is drawn or written
  if (!samples) return report_error(samples.error().message);
  auto view = lod::make_view(*camera);
  if (!view) return report_error(view.error().message);
  if (const tiles::Store* store = elevation_of(setup)) {
    // Below the ground: the terrain under the eye, at the finest level.
    auto ground = store->sample(camera->lon, camera->lat, store->manifest().max_level);
    if (!ground) return report_error(ground.error().message);
    if (*ground && camera->height < **ground) {
      return report_error(
          fmt::format("{}: the camera at {:.1f} m is below the ground ({:.1f} m) at {},{}",
                      args.get("--camera") ? "--camera" : "--look-at", camera->height, **ground,
                      camera->lon, camera->lat));
    }
  }

  // Complete frame: every tile read first. The brute-force reference
  // (--full-resolution) has one vertex per finest sample, no deeper quads.
  view::SceneOptions so = scene_options(setup);
  so.interactive = false;
  auto context = render::GlContext::create_headless();
  if (!context) return report_error(context.error().message);
  auto target = render::make_offscreen_target(setup.width, setup.height);
  if (!target) return report_error(target.error().message);
  auto scene = view::Scene::create(elevation_of(setup), setup.imagery ? &*setup.imagery : nullptr,
                                   so, steady_clock());
  if (!scene) return report_error(scene.error().message);
  auto frame = (*scene)->draw(*camera, **target);
  if (!frame) return report_error(frame.error().message);
  auto pixels = (*target)->read_rgba();
  if (!pixels) return report_error(pixels.error().message);
  const std::string out = *args.get("--output");
  if (auto st = write_png(out, *pixels, setup.width, setup.height); !st) {
    return report_error(st.error().message);
  }
  if (auto path = args.get("--stats")) {
    nlohmann::json stats = stats_json((*scene)->last_selection(), frame->draw);
    if (const int n = samples->value_or(20000); n > 0) {
      auto measured = (*scene)->measure_last_frame(*camera, n);
      if (!measured) return report_error(measured.error().message);
      stats["measured_error"] = {{"max_pixels", measured->max_pixels},
                                 {"samples", measured->samples}};
    }
    if (frame->refine) {
      stats["refine"] = {{"ms", frame->refine->seconds * 1e3},
                         {"marks_evaluated", frame->refine->marks_evaluated},
                         {"criteria_ms", frame->refine->criteria_seconds * 1e3},
                         {"marks_near", frame->refine->marks_near},
                         {"tiles_measured", frame->refine->tiles_measured},
                         {"tiles_prepared", frame->refine->tiles_prepared},
                         {"too_coarse_quads", frame->refine->too_coarse},
                         {"unresolved_diamonds", frame->refine->unresolved}};
    }
    if (setup.detect) {
      nlohmann::json hints = nlohmann::json::array();
      for (const view::TargetHint& h : (*scene)->last_hints()) {
        hints.push_back({{"lon", h.lon},
                         {"lat", h.lat},
                         {"amplitude", h.detection.amplitude},
                         {"pslr_db", h.detection.pslr_db},
                         {"axes_deg", {h.detection.direction[0], h.detection.direction[1]}}});
      }
      stats["hints"] = hints;
    }
    if (auto st = write_json(*path, stats.dump(1)); !st) {
      return report_error(st.error().message);
    }
  }
  std::printf(
      "wrote %s: %dx%d, %u quads, %llu triangles (%.2f per pixel), %u draw calls, "
      "selection %.2f ms, gpu %.1f ms\n",
      out.c_str(), setup.width, setup.height, frame->selection.quads,
      static_cast<unsigned long long>(frame->draw.triangles), frame->draw.triangles_per_pixel(),
      frame->draw.draw_calls, frame->selection.seconds * 1e3, frame->draw.gpu_seconds * 1e3);
  return 0;
}

}  // namespace

int run_render(const std::vector<std::string>& command_line) {
  if (wants_help(command_line)) return print_help(help_with_layer_options(kRenderHelp).c_str());
  // Layer options repeat and their order matters: taken out first.
  std::vector<std::string> argv = command_line;
  auto layers = take_layer_options(argv);
  if (!layers) return report_error(layers.error().message);
  auto args = Args::parse(argv,
                          with_scene_options({{"--output", "-o"},
                                              {"--path"},
                                              {"--mesh-level"},
                                              {"--full-resolution", "", false},
                                              {"--stats"},
                                              {"--error-samples"},
                                              {"--simulate-latency"},
                                              {"--simulate-bandwidth"},
                                              {"--mode"},
                                              {"--fps"},
                                              {"--loads"},
                                              {"--no-prefetch", "", false},
                                              {"--pager"},
                                              {"--until-complete"},
                                              {"--max-frames"},
                                              {"--events"},
                                              {"--no-frames", "", false},
                                              {"--codec"},
                                              {"--crf"},
                                              {"--preset"},
                                              {"--parallel"},
                                              {"--composite"},
                                              {"--parallel-timeout"}}),
                          "render");
  if (!args) return report_error(args.error().message);
  if (!args->get("--output")) return report_error("render: -o is required");
  if (args->get("--path") && (args->get("--camera") || args->get("--look-at"))) {
    return report_error("render: --path replaces --camera and --look-at");
  }
  if (!args->get("--path")) {
    if (is_movie_output(*args->get("--output"))) return report_error("-o: a movie needs --path");
    for (const char* name : {"--codec", "--crf", "--preset"}) {
      if (args->get(name)) return report_error(std::string(name) + ": only for a movie (--path)");
    }
  }
  if (auto safe = check_render_outputs(*args, layers->textures.paths); !safe) {
    return report_error(safe.error().message);
  }
  if (args->get("--composite") && !args->get("--parallel")) {
    return report_error("--composite: only with --parallel sort-last:...");
  }
  if (args->get("--parallel")) {
    if (!layers->textures.layers.empty())
      return report_error("--parallel: not with --texture layers yet");
    if (!layers->elevation.empty()) return report_error("--parallel: not with --elevation-op yet");
    return render_parallel(*args);
  }
  auto setup = parse_render_setup(*args, std::move(layers->textures), std::move(layers->elevation));
  if (!setup) return report_error(setup.error().message);
  if (args->get("--path")) {
    keep_freed_memory();  // frame after frame
    prefault_frame_heap(kFrameHeapBytes);
    return render_path(*args, *setup);
  }
  return render_still(*args, *setup);
}

}  // namespace relief::cli
