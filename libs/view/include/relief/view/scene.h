#pragma once
// The frame loop's core, shared by `relief render` (stills and paths), the
// viewer, the movie exporter and the cluster renderer: a scene of an
// elevation store and an optional draped imagery store with their loaders,
// the terrain model, the level-of-detail selection and the renderer. Each
// call to draw() makes one frame of a camera: selection over what is resident
// (interactive) or over everything (complete frames, which wait for their
// tiles), requests in view priority, prefetch along the camera's motion,
// drawing. Time comes from an injected Clock.
//
// Used on the thread that owns the GL context (the renderer's rule); the
// loaders' threads are internal.
#include <functional>
#include <memory>
#include <optional>
#include <span>
#include <vector>

#include "relief/base/clock.h"
#include "relief/base/result.h"
#include "relief/lod/measured_error.h"
#include "relief/lod/refine.h"
#include "relief/lod/selection.h"
#include "relief/render/terrain_renderer.h"
#include "relief/stream/tile_loader.h"
#include "relief/view/target_hints.h"

namespace relief::view {

struct SceneOptions {
  // Interactive frames never wait for I/O: tiles load on the loaders' threads
  // and frames draw what is resident. Complete frames read every tile they
  // need first.
  bool interactive = true;
  stream::LoaderOptions loader;  // elevation; its memory budget also bounds complete frames' cache
  uint64_t imagery_budget = uint64_t{512} << 20;  // the imagery loader's memory budget
  uint64_t gpu_budget = uint64_t{1} << 30;
  // > 0: one budget for every tile cache the scene keeps in main memory,
  // split by split_memory_budget (memory_budget.h) into loader.memory_budget,
  // diamond_error_budget and imagery_budget, and gpu_budget too when the GL
  // rasterises on the CPU unless gpu_budget_given. 0: the budgets as set.
  uint64_t memory_budget = 0;
  bool gpu_budget_given = false;
  // Edge marks: the diamond errors' budget (0: loader.memory_budget again).
  uint64_t diamond_error_budget = 0;
  int mesh_level = 4;
  // selection.mode == LodMode::edge_marks: each frame's quads are refined by
  // edge marks (lod/refine.h) with this variant, the per-diamond errors of
  // data tiles cached within diamond_error_budget (they take ~4 times the
  // bytes of the decoded tile).
  lod::SelectionOptions selection;
  lod::RefineVariant refine_variant = lod::RefineVariant::kTopDown;
  // Threads that refine a frame's quads (top-down; the same mesh): 1, the
  // thread that draws; 0, one per core. More than one: a pool of them kept
  // by the scene, the drawing thread one of them.
  unsigned refine_threads = 1;
  // Every diamond's split criterion evaluated by a GL compute shader
  // (render::GlRefineCriteria, created in the drawing thread's context at the
  // first refinement) before the refinement looks them up: the same mesh.
  // On llvmpipe it is 20-250 times slower than the CPU's top-down refinement
  // (docs/refinement.md, "Split criteria on the GPU").
  bool refine_on_gpu = false;
  // Edge marks, interactive frames: the quads a frame's refinement wanted
  // split (RefineStats::split_wanted), the next frames' selection splits
  // (lod/split_feedback.h), and a frame that wanted any is not complete.
  // Off by default: such frames then depend on the frames before them and
  // may draw more than the complete frame of their camera.
  bool split_feedback = false;
  render::RenderOptions render;
  // Prefetch: while the camera moves, also request what a selection this
  // many frames ahead on the same motion would want (at lower priority).
  bool prefetch = true;
  double lookahead_frames = 10;
  // > 0: load every tile within this many tile sizes of the eye instead of by
  // view priority (the radius pager, a baseline for benchmarks).
  double radius_tiles = 0;
  // Interactive scenes, > 0: a frame draws at most this many elevation tiles
  // that are not on the GPU yet (it uploads them, ~0.2 ms each with their
  // slopes on llvmpipe); quads whose children's tiles would pass it stay
  // whole until a later frame (SelectionStats::deferred; such a frame is not
  // complete and draws_more). The tiles admitted are uploaded even when the
  // selection ends up not drawing them, so every frame makes progress.
  // 0: no budget (a frame where many tiles arrive at once uploads them all).
  uint32_t uploads_per_frame = 0;
  // Full-resolution mesh (brute force reference; stills only).
  bool full_resolution = false;
  // Texture layers draped instead of the imagery store (which must then be
  // null: give it as an RGBA layer), bottom first, processed and composited
  // per quad on the GPU (docs/gpu-processing.md, "Draw-time processing").
  // Their `tiles` are the scene's: loaders of `imagery_budget` each in
  // interactive frames.
  std::vector<render::TextureLayer> texture_layers;
  // Detector hints (target_hints.h) over the first SAR texture layer: the
  // point targets of the tiles each frame shows, drawn over the frame.
  bool detect = false;
  process::DetectorParams detector;
  // Given to the renderer (TerrainRenderer::set_on_growth_ahead): the bytes
  // a texture array's next growth will allocate, before it comes.
  std::function<void(uint64_t bytes)> on_growth_ahead;
  // Interactive scenes: called on the thread that finished it each time
  // asynchronous work ends that a later frame of the same camera may draw:
  // a tile load of any loader (LoaderOptions::on_settled, after the
  // loader's own), a texture-layer tile processed on the CPU, a tile's
  // hints detected. Thread-safe and quick; the
  // viewer wakes its window with it (docs/viewer.md, "Idle").
  std::function<void()> on_change;
};

struct FrameReport {
  lod::Camera camera;
  lod::SelectionStats selection;
  std::optional<lod::RefineStats> refine;  // edge-mark frames
  size_t refine_cache_tiles = 0;           // data tiles with cached diamond errors
  uint64_t refine_cache_bytes = 0;
  // After the frame, the bytes SceneOptions::memory_budget bounds (the
  // loaders' resident tiles, the diamond errors, and L3 when it is main
  // memory; counted whether or not a memory budget was given, L3 only with one).
  uint64_t cached_bytes = 0;
  render::FrameStats draw;
  double frame_seconds = 0;  // selection to the end of drawing, on the clock
  // Of frame_seconds on the clock: selection with its requests and prefetch
  // (refinement and drawing are in refine and draw).
  double select_seconds = 0;
  double cpu_seconds = 0;  // the same without the wait for the GPU
  // Page faults the frame took on the thread that drew it (thread_page_faults).
  uint64_t page_faults = 0;
  // Everything this frame wanted was resident and drawn (elevation and
  // imagery): the frame equals the complete frame of its camera.
  bool complete = false;
  // SceneOptions::detect: hints drawn, and tiles whose hints are still being
  // detected (interactive frames; such a frame is not complete).
  size_t hints = 0, hint_tiles_pending = 0;
  // The next frame of the same camera may draw more without waiting for
  // anything (splits fed back, texture-layer composites made in this frame
  // and maybe more past its processing budget): a loop waiting for
  // on_change on an incomplete view draws again at once instead.
  bool draws_more = false;
};

class Scene {
 public:
  // `elevation` and `imagery` (may be null) and `clock` must outlive the
  // scene. Needs a current GL context.
  static Result<std::unique_ptr<Scene>> create(const tiles::Store& elevation,
                                               const tiles::Store* imagery,
                                               const SceneOptions& options, const Clock& clock);
  // `elevation` may be null: the bare ellipsoid, under texture layers.
  static Result<std::unique_ptr<Scene>> create(const tiles::Store* elevation,
                                               const tiles::Store* imagery,
                                               const SceneOptions& options, const Clock& clock);
  ~Scene();
  Scene(const Scene&) = delete;
  Scene& operator=(const Scene&) = delete;

  // One frame of `camera` into `target`. `before_drawing`, when given, is
  // called once the frame's selection and refinement are made, before its
  // first GL call: the viewer swaps the previous frame there, so that
  // frame's rasterisation (llvmpipe's threads) overlaps this one's CPU work.
  Result<FrameReport> draw(const lod::Camera& camera, render::RenderTarget& target,
                           const std::function<void()>& before_drawing = {});
  // The next frame does not continue the previous one's motion (a cut in a
  // path, a jump in the viewer): no prefetch between them.
  void cut();
  // Interactive scenes: the asynchronous work that ended so far (what
  // SceneOptions::on_change announces), and a wait of at most `seconds` of
  // real time (a safety timeout) until more did than `seen`; whether it did.
  // A loop with nothing else to do waits here rather than redraw an
  // incomplete still view (play_path after the path's end).
  uint64_t changes() const;
  bool wait_for_change(uint64_t seen, double seconds) const;

  const SceneOptions& options() const;
  // A known path (movie export): every interactive frame also requests, at
  // prefetch priority, what the selection of this camera of a coming frame
  // wants, instead of extrapolating the motion. nullopt: back to that.
  void set_prefetch_camera(std::optional<lod::Camera> camera);
  // Interactive scenes: the selection of `camera` and its requests (with the
  // prefetch camera's), without drawing. Returns the quads still waiting for
  // elevation data (0: a draw() of `camera` now needs no more).
  Result<uint32_t> request(const lod::Camera& camera);

  // Changes that act from the next frame (the viewer's panels, speed-dependent LOD).
  void set_pixel_error(double pixels);
  void set_render_options(const render::RenderOptions& options);
  // New parameters of the texture layers (chain, range, colour map, opacity;
  // the same stores in the same order as options().texture_layers; their
  // `tiles` are ignored): the next frame shows no tile processed with the
  // old ones. The viewer's layer panels call this.
  Status set_texture_layers(std::vector<render::TextureLayer> layers);
  // Frozen: frames draw the last frame's selection (and refined mesh) from
  // the new camera, without selecting, requesting or prefetching, so culling
  // and level of detail can be inspected from outside (the LOD panel). Its
  // tiles stay pinned. Frozen frames are never complete.
  void set_selection_frozen(bool frozen);
  bool selection_frozen() const;
  lod::TerrainModel& terrain();
  const lod::Selection& last_selection() const;  // of the last draw()
  const lod::RefinedMesh* last_refined() const;  // of the last draw(), edge-mark frames
  // SceneOptions::detect: the hints the last frame drew, and their detector
  // (for the analysis of one); null without detection.
  const std::vector<TargetHint>& last_hints() const;
  TargetHints* target_hints();
  // The last frame's measured screen error (lod/measured_error.h) over
  // `samples` random finest samples.
  Result<lod::MeasuredError> measure_last_frame(const lod::Camera& camera, int samples);
  // The same at given data points (lod::measure_screen_error_at): pixels per
  // point, nullopt where the last frame drew nothing there or it is off screen.
  Result<std::vector<std::optional<double>>> measure_last_frame_at(
      const lod::Camera& camera, std::span<const lod::DataPoint> points);
  // Null for complete frames (no loaders) or without imagery.
  stream::TileLoader* elevation_loader();
  stream::TileLoader* imagery_loader();

 private:
  struct Impl;
  explicit Scene(std::unique_ptr<Impl> impl);
  std::unique_ptr<Impl> impl_;
};

}  // namespace relief::view
