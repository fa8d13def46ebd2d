#pragma once
// The viewer's state, shared by its loop (viewer.cpp) and its panels
// (panels.cpp).
#include <atomic>
#include <deque>
#include <future>
#include <map>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "relief/view/ground.h"
#include "relief/view/lens_drag.h"
#include "relief/window/viewer.h"

namespace relief::window {

// Tiles loaded since the loader was last idle against those still to load:
// the load progress bar.
struct LoadProgress {
  uint64_t base = 0;  // loaded + failed when the loader was last idle
  uint64_t done = 0, pending = 0;
  void update(const stream::LoaderStats& s) {
    pending = uint64_t{s.queued} + s.in_flight;
    if (pending == 0) base = s.loaded + s.failed;
    done = s.loaded + s.failed - base;
  }
  float fraction() const {
    return pending == 0 ? 1.0f : static_cast<float>(done) / static_cast<float>(done + pending);
  }
};

// Loads per second over about the last second.
struct LoadRate {
  double time = -1;
  uint64_t loaded = 0, failed = 0;
  double loads_per_s = 0, failures_per_s = 0;
  void update(double now, const stream::LoaderStats& s) {
    if (time < 0) {
      time = now, loaded = s.loaded, failed = s.failed;
    } else if (now - time >= 1) {
      loads_per_s = static_cast<double>(s.loaded - loaded) / (now - time);
      failures_per_s = static_cast<double>(s.failed - failed) / (now - time);
      time = now, loaded = s.loaded, failed = s.failed;
    }
  }
};

struct Viewer::Impl {
  Impl(Window& w, const tiles::Store* e, const tiles::Store* i, const view::SceneOptions& so,
       const ViewerOptions& o, const Clock& c)
      : window(w),
        elevation(e),
        imagery(i),
        scene_options(so),
        options(o),
        clock(c),
        speed_lod(o.speed_lod),
        frame_budget(o.frame_budget) {}

  Window& window;
  const tiles::Store* elevation;  // null: the bare ellipsoid
  const tiles::Store* imagery;
  view::SceneOptions scene_options;  // pixel_error: the still threshold
  ViewerOptions options;
  const Clock& clock;

  std::unique_ptr<view::Scene> scene;
  bool imagery_on = true, imagery_wanted = true;  // the panel sets wanted; the next frame acts
  std::unique_ptr<view::Controller> controller;
  view::SpeedLod speed_lod;
  view::FrameBudget frame_budget;
  double last_frame_ms = 0;  // the previous frame's period (0: none yet)
  double threshold = 1;      // this frame's pixel error
  bool frozen = false;       // the LOD panel's "freeze selection"

  std::optional<Clock::TimePoint> start, last;  // of the session; of the last frame() or frame
  double last_cpu = 0;                          // the process's CPU time at drawn_start, seconds
  double time = 0;
  std::optional<double> path_end;  // when playback reached the end
  bool quit = false;

  bool recording = false, record_cut = false;
  std::vector<lod::Keyframe> recorded;
  std::future<Status> export_job;  // export_recorded()'s, while running
  std::string export_status;       // the Path panel's line

  size_t index = 0;
  size_t skipped = 0;  // frames not drawn: idle
  // After the last frame: draw the next at once (no), or wait for an event
  // first, the view being still and complete (complete) or still and
  // waiting for the scene's asynchronous work (waiting: a wake, or
  // idle_wait_seconds on the clock, draws too).
  enum class Idle { no, complete, waiting };
  Idle idle = Idle::no;
  // The scene's asynchronous work that ended (SceneOptions::on_change), and
  // whether the window was woken for it since frame() last began a wait
  // (one empty event per wait is enough). Shared with the loaders' threads.
  struct Wakeup {
    std::atomic<uint64_t> changes{0};
    std::atomic<bool> posted{false};
  };
  std::shared_ptr<Wakeup> wakeup = std::make_shared<Wakeup>();
  std::optional<lod::Camera> drawn_camera;  // the last frame's
  uint64_t drawn_events = 0;                // window events when the last frame was drawn
  std::string drawn_export_status;          // export_status then
  uint64_t drawn_changes = 0;               // wakeup->changes when it started
  Clock::TimePoint drawn_start;             // when it started, on the clock
  double waited = 0;  // seconds frame() spent in idle waits since then: not frame time
  std::optional<view::FrameReport> report;  // the last frame's
  std::vector<double> frame_ms;             // every frame's period but the last's
  std::deque<double> recent_ms;             // the panels' window
  std::vector<ViewerFrame> frames;
  std::vector<std::string> screenshots;
  // Tiles whose last load failed (the loader's message, which names the
  // file), by layer and key; a later load of the tile takes it out.
  std::map<std::string, std::string> unreadable;
  bool panels = true;

  std::string layer_error;                              // the texture-layer panel's refused change
  std::optional<std::pair<int64_t, int64_t>> analysed;  // the target analysed, by sample
  std::optional<process::TargetAnalysis> analysis;

  double cursor_x = -1, cursor_y = -1;
  std::optional<view::Pick> pick;
  // A lens grabbed by a left press inside its circle (Control held: the
  // press is the camera's): the next frame moves its centre to the terrain
  // point under the cursor, until the release.
  struct LensDrag {
    view::LensRef lens;
    double x = 0, y = 0;  // the cursor, pixels
    bool moved = false;   // since the last frame
    bool released = false;
  };
  std::optional<LensDrag> lens_drag;
  LoadProgress progress;
  LoadRate elevation_rate, imagery_rate;

  Status make_scene();
  void on_input(const view::InputEvent& e);
  void on_window_key(view::Key key);
  // A press inside a lens's circle on the last frame's terrain starts a drag.
  bool grab_lens(const view::InputEvent& e);
  // The dragged lens to the terrain point under the cursor in `camera`.
  void move_dragged_lens(const lod::Camera& camera, const view::Ground& ground);
  void record(const lod::Camera& camera);
  bool export_recorded();
  void poll_export();      // a finished export's status into export_status
  void take_screenshot();  // F12: the next free relief_NNNN.png in screenshot_dir
  Status write_screenshot(const std::string& path);
};

// Dear ImGui panels: layers, level of detail, caches, frame statistics,
// cursor read-out and load progress.
void draw_panels(Viewer::Impl& v);

}  // namespace relief::window
