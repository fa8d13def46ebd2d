#pragma once
// The interactive viewer's loop (`relief view`): each frame polls the
// window's input, moves the camera by the active controller over the time
// since the previous frame (on the injected clock), relaxes the pixel error
// with the view's speed, draws the scene into the window (never waiting for
// I/O), draws the panels over it and swaps. Scripted sessions play a path
// through the playback controller and end when it is done.
//
// Keys the viewer keeps for itself (everything else goes to the controller):
//   Tab, F1  panels on/off        F8   vsync on/off
//   F9       recording on/off     F11  fullscreen
//   F10      export recorded path F12  screenshot (PNG)     Escape  quit
// and a left press inside a texture layer's lens (without Control), which
// drags the lens over the terrain until the release (docs/viewer.md).
#include <functional>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "relief/base/clock.h"
#include "relief/base/result.h"
#include "relief/lod/camera_path.h"
#include "relief/view/controller.h"
#include "relief/view/frame_budget.h"
#include "relief/view/path_file.h"
#include "relief/view/scene.h"
#include "relief/view/speed_lod.h"
#include "relief/window/window.h"

namespace relief::window {

struct ViewerOptions {
  view::ControlMode mode = view::ControlMode::orbit;
  lod::Camera start;                   // viewport: replaced by the window's
  view::ControllerOptions controller;  // playback: the path
  view::SpeedLodOptions speed_lod;
  // While the view moves, frames over this budget relax the threshold
  // further and frames well within it relax it less than the speed does,
  // never below the still threshold (view/frame_budget.h); a still view is
  // drawn at the still threshold whatever it costs. target_ms 0: no budget.
  view::FrameBudgetOptions frame_budget;
  // Scripted sessions: quit once the path has ended (at once without one)
  // and a frame is complete, or `until_complete` seconds after it ended.
  bool exit_when_done = false;
  double until_complete = 30;
  bool record = false;     // recording from the first frame (F9 toggles it)
  double record_fps = 30;  // the "fps" of the path file written
  std::string screenshot_dir = ".";
  bool panels = true;
  bool collect_frames = false;  // keep every frame's record (for --stats)
  // Overlap (docs/viewer.md): while frames follow one another at once, a
  // frame is swapped to the screen by the next one, after that one's
  // selection and refinement, which run while the GL (llvmpipe's threads)
  // still draws it; the screen is then one frame behind the target. On by
  // default: on a quiet 2-core machine it gave 20 % more frames per second
  // on both bench/view flights (docs/viewer.md). Off: every frame waits for
  // the GL and is swapped before frame() returns.
  bool overlap = true;
  // The scene's refine threads left to the viewer (SceneOptions::refine_threads
  // not chosen by the user): on a software rasteriser with overlap, the
  // render thread alone, as the cores rasterise the previous frame while a
  // frame refines and lanes only contend with them (bench/view: the same
  // fps, p99 a little worse); the scene's refine_threads otherwise.
  bool refine_threads_auto = false;
  // Idle: once the camera is still (no input, not recording: the path
  // would glide through the pause; not playing a path), frame() waits up to
  // this long for an event instead of drawing. A complete frame (at the
  // still threshold, or the selection frozen) is drawn again only when one
  // came (input, a resize, an exposure) or an export finished. An
  // incomplete one also when the scene's asynchronous work brought
  // something (a tile arrived: its loader wakes the window), or after this
  // long on the clock (a failed tile is asked for again by a frame); unless
  // the next frame draws more anyway (FrameReport::draws_more, a threshold
  // still relaxed after the motion), which it then does at once. 0: always
  // draw.
  double idle_wait_seconds = 0.25;
  // "Export recorded path" (F10, the Path panel's button): called on a
  // thread of its own with the path recorded so far while frames keep
  // drawing (`relief view` writes it and, with --export-movie, renders it as
  // a movie). Null: nothing to export to.
  std::function<Status(const view::PathFile& path)> export_path;
};

// One frame as the statistics see it.
struct ViewerFrame {
  size_t index = 0;
  double time = 0;  // seconds since the session started, on the clock
  // This frame's period: from its start to the next frame's (1000 / fps),
  // idle waits between them left out; 0 for the last frame (no next one).
  double frame_ms = 0;
  double draw_ms = 0;      // the scene's frame: selection to the end of drawing
  double pixel_error = 0;  // the threshold used (relaxed by speed and frame budget)
  lod::Camera camera;
  uint32_t quads = 0;
  uint64_t triangles = 0;
  double triangles_per_pixel = 0;
  uint64_t uploaded_bytes = 0;  // geometry and textures
  bool complete = false;
  // Edge-mark refinement (0 in the quad mode): wall-clock and the render
  // thread's CPU time, split criteria evaluated, and those of the quads
  // whose last decisions were reused (lod::RefineHistory).
  double refine_ms = 0, refine_cpu_ms = 0;
  uint64_t marks_evaluated = 0, marks_reused = 0;
  // --lod edge-marks-gl: the compute shader's time, and the diamonds it left
  // to the CPU (too near the threshold).
  double criteria_ms = 0;
  uint64_t marks_near = 0;
  uint32_t quads_reused = 0;
  // Data tiles whose diamond errors the refinement measured on the render
  // thread (not prepared by the loaders, or dropped by the cache's budget).
  uint32_t tiles_measured = 0;
  // Where the frame went, on the clock (ms): the scene's selection with its
  // requests, the renderer's preparation (records, tile textures and their
  // uploads), issuing the draw calls (submit: llvmpipe shades vertices and
  // bins on this thread) and, without overlap, the wait for the GL to draw
  // (gpu: submit and the rasterisation, to glFinish); swap: the wait for the
  // previous frame's swap (overlap: the rest of its rasterisation, within
  // draw_ms); present: this frame's copy to the screen and panels (and its
  // swap without overlap).
  double select_ms = 0, prepare_ms = 0, gpu_ms = 0, submit_ms = 0, swap_ms = 0, present_ms = 0;
  uint32_t tiles_uploaded = 0;  // tile textures uploaded by this frame (L3 misses)
  // Splits held back for the budget of uploads per frame (SelectionStats::deferred).
  uint32_t uploads_deferred = 0;
  uint64_t page_faults = 0;   // on the render thread (view::FrameReport)
  uint64_t cached_bytes = 0;  // what --memory-budget bounds (view::FrameReport)
  // CPU time of the whole process (render, loaders, llvmpipe's threads)
  // over the same period, idle waits included (the loaders work in them):
  // what a frame costs on a shared machine. 0 for the last frame.
  double process_cpu_ms = 0;
  // The relaxations in pixel_error: the speed's and the frame budget's factors.
  double speed_factor = 1, budget_factor = 1;
};

struct ViewerSummary {
  size_t frames = 0;          // drawn
  size_t skipped_frames = 0;  // frame() calls that drew nothing: idle, nothing changed
  double seconds = 0;
  double p50_frame_ms = 0, p99_frame_ms = 0;  // of the periods of every frame but the last
  bool complete = false;                      // the last frame
  bool path_finished = false;                 // playback reached the path's end
  std::vector<ViewerFrame> frames_list;       // collect_frames only
  std::vector<lod::Keyframe> recorded;        // the cameras recorded
  std::vector<std::string> screenshots;       // files written by F12
  // exit_when_done: the clock time (ViewerFrame::time) of the first frame
  // drawn at the path's end (or, without a path, of the first frame).
  std::optional<double> path_end;
  // The errors of tiles (elevation, imagery) whose last load failed, each
  // naming the tile's file: a corrupt or missing tile the view went without.
  std::vector<std::string> unreadable_tiles;
};

class Viewer {
 public:
  // `elevation` (null: the bare ellipsoid, under texture layers), `imagery`
  // (may be null), `window` and `clock` outlive the viewer. The scene is
  // made here (and again when the imagery layer is switched on or off).
  static Result<std::unique_ptr<Viewer>> create(Window& window, const tiles::Store* elevation,
                                                const tiles::Store* imagery,
                                                const view::SceneOptions& scene,
                                                const ViewerOptions& options, const Clock& clock);
  ~Viewer();
  Viewer(const Viewer&) = delete;
  Viewer& operator=(const Viewer&) = delete;

  // One frame. False when the session is over (window closed, Escape, or a
  // scripted session done).
  Result<bool> frame();
  // frame() until the session is over.
  Result<ViewerSummary> run();
  ViewerSummary summary() const;

  // What input reaches (window.deliver() goes through here).
  view::Controller& controller();
  void set_controller(std::unique_ptr<view::Controller> controller);
  view::Scene& scene();
  bool panels_visible() const;
  bool recording() const;
  // Starts export_path with the path recorded so far (F10). False, with the
  // reason in the Path panel, when an export is running, nothing was
  // recorded or there is no export_path.
  bool export_recorded();
  // Waits for the running export, if any, and returns its status.
  Status wait_for_export();
  // The last frame's pixels (terrain only) as a PNG, atomically.
  Status screenshot(const std::string& path);

  struct Impl;

 private:
  explicit Viewer(std::unique_ptr<Impl> impl);
  std::unique_ptr<Impl> impl_;
};

// Writes RGBA pixels (top row first) as a PNG, atomically.
Status write_png(const std::string& path, std::span<const uint8_t> rgba, int width, int height);

}  // namespace relief::window
