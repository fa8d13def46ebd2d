#include "relief/window/viewer.h"

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <ctime>
#include <filesystem>

#include <fmt/format.h>

#include "relief/base/file_io.h"
#include "relief/tiles/codec.h"
#include "relief/view/path_player.h"
#include "viewer_state.h"

namespace relief::window {

namespace {
constexpr size_t kRecentFrames = 120;  // the panels' statistics window

bool same_camera(const lod::Camera& a, const lod::Camera& b) {
  return a.lon == b.lon && a.lat == b.lat && a.height == b.height && a.heading == b.heading &&
         a.pitch == b.pitch && a.roll == b.roll && a.fov_y == b.fov_y && a.width == b.width &&
         a.height_px == b.height_px;
}
}  // namespace

Status write_png(const std::string& path, std::span<const uint8_t> rgba, int width, int height) {
  tiles::Raster image(tiles::SampleType::UInt8, 4, width, height);
  std::copy(rgba.begin(), rgba.end(), image.u8().begin());
  auto png = RELIEF_TRY(tiles::encode(image, tiles::CodecOptions{tiles::Codec::Png}));
  return write_file_atomic(path, png);
}

Status Viewer::Impl::make_scene() {
  scene.reset();  // its GPU memory goes before the new one's arrives
  view::SceneOptions so = scene_options;
  const tiles::Store* layer = imagery_on ? imagery : nullptr;
  if (!layer && so.selection.texture == imagery) so.selection.texture = nullptr;
  // A tile arrived (or hints were detected): an idle frame() waiting for it
  // wakes up. Called on the loaders' threads, which the scene joins before
  // it goes; the window outlives the viewer.
  so.on_change = [wakeup = wakeup, w = &window] {
    ++wakeup->changes;
    if (!wakeup->posted.exchange(true)) w->wake();
  };
  scene = RELIEF_TRY(view::Scene::create(elevation, layer, so, clock));
  // On the render thread (the loader's begin_frame), as the map is used.
  for (auto [name, loader] : {std::pair{"elevation", scene->elevation_loader()},
                              std::pair{"imagery", scene->imagery_loader()}}) {
    if (!loader) continue;
    loader->subscribe([this, name](const stream::TileEvent& e) {
      const std::string key = std::string(name) + " " + e.key.to_string();
      if (e.kind == stream::TileEventKind::Failed) unreadable[key] = e.error;
      if (e.kind == stream::TileEventKind::Loaded) unreadable.erase(key);
    });
  }
  scene->set_selection_frozen(frozen);  // a new scene has no selection yet: frozen from its first
  progress = {};
  return {};
}

namespace {

// Keys the viewer keeps: neither their press nor their release reaches the controller.
bool viewer_key(view::Key key) {
  using view::Key;
  return key == Key::tab || key == Key::f1 || key == Key::f8 || key == Key::f9 || key == Key::f10 ||
         key == Key::f11 || key == Key::f12 || key == Key::escape;
}

}  // namespace

void Viewer::Impl::on_window_key(view::Key key) {
  using view::Key;
  switch (key) {
    case Key::tab:
    case Key::f1:
      panels = !panels;
      break;
    case Key::f8:
      window.set_vsync(!window.vsync());
      break;
    case Key::f9:
      recording = !recording;
      record_cut = recording && !recorded.empty();  // a resumed recording jumps
      break;
    case Key::f10:
      export_recorded();
      break;
    case Key::f11:
      window.toggle_fullscreen();
      break;
    case Key::f12:
      take_screenshot();
      break;
    case Key::escape:
      quit = true;
      break;
    default:
      break;
  }
}

void Viewer::Impl::on_input(const view::InputEvent& e) {
  using Type = view::InputEvent::Type;
  if ((e.type == Type::key_down || e.type == Type::key_up) && viewer_key(e.key)) {
    if (e.type == Type::key_down) on_window_key(e.key);
    return;
  }
  const bool left = e.button == view::MouseButton::left;
  if (e.type == Type::mouse_down && left && grab_lens(e)) return;
  if (e.type == Type::mouse_up && left && lens_drag) {
    lens_drag->x = e.x, lens_drag->y = e.y;
    lens_drag->moved = lens_drag->released = true;
    return;  // the controller never saw the press
  }
  if (e.type == Type::cursor) {
    cursor_x = e.x, cursor_y = e.y;
    if (lens_drag) lens_drag->x = e.x, lens_drag->y = e.y, lens_drag->moved = true;
  }
  controller->push(e);  // cursor moves too: without its press a mode does not drag
}

bool Viewer::Impl::grab_lens(const view::InputEvent& e) {
  if ((e.modifiers & view::kControl) || !drawn_camera || !scene) return false;
  const std::vector<render::TextureLayer>& layers = scene_options.texture_layers;
  if (std::none_of(layers.begin(), layers.end(),
                   [](const render::TextureLayer& l) { return !l.lenses.empty(); })) {
    return false;
  }
  const auto at = view::pick(*drawn_camera, e.x, e.y, view::resident_ground(*scene));
  if (!at) return false;
  const auto lens = view::lens_at(layers, at->lon, at->lat);
  if (!lens) return false;
  lens_drag = LensDrag{*lens, e.x, e.y, false, false};
  return true;
}

void Viewer::Impl::move_dragged_lens(const lod::Camera& camera, const view::Ground& ground) {
  if (!lens_drag || !lens_drag->moved) return;
  const LensDrag drag = *lens_drag;
  lens_drag->moved = false;
  if (drag.released) lens_drag.reset();
  const auto at = view::pick(camera, drag.x, drag.y, ground);
  if (!at) return;  // over the sky the lens stays where it was
  std::vector<render::TextureLayer>& layers = scene_options.texture_layers;
  render::Lens& lens = layers[drag.lens.layer].lenses[drag.lens.lens];
  lens.lon = at->lon, lens.lat = at->lat;
  // As a panel's change: refused, it is taken back and said in the panel.
  if (auto st = scene->set_texture_layers(layers); !st) {
    layer_error = st.error().message;
    layers = scene->options().texture_layers;
  }
}

void Viewer::Impl::record(const lod::Camera& camera) {
  // Keyframe times must increase: a frame drawn at the same instant as the
  // previous one (a clock that did not move) adds nothing.
  if (!recorded.empty() && !(time > recorded.back().time)) return;
  recorded.push_back({time, camera, record_cut});
  record_cut = false;
}

bool Viewer::Impl::export_recorded() {
  poll_export();
  if (export_job.valid()) return false;  // the running export's line stays
  if (!options.export_path) {
    export_status = "nothing to export to";
    return false;
  }
  if (recorded.empty()) {
    export_status = "nothing recorded (F9 starts recording)";
    return false;
  }
  export_status = fmt::format("exporting {} keyframes...", recorded.size());
  // A copy: recording goes on while the export runs.
  export_job = std::async(std::launch::async, options.export_path,
                          view::PathFile{options.record_fps, recorded});
  return true;
}

void Viewer::Impl::poll_export() {
  using namespace std::chrono_literals;
  if (!export_job.valid() || export_job.wait_for(0s) != std::future_status::ready) return;
  const Status st = export_job.get();
  export_status = st ? "exported" : "export failed: " + st.error().message;
}

Status Viewer::Impl::write_screenshot(const std::string& path) {
  render::RenderTarget& target = window.target();
  const std::vector<uint8_t> pixels = RELIEF_TRY(target.read_rgba());
  RELIEF_CHECK(write_png(path, pixels, target.width(), target.height()));
  screenshots.push_back(path);
  return {};
}

void Viewer::Impl::take_screenshot() {
  if (!report) return;
  std::filesystem::path path;
  for (int n = static_cast<int>(screenshots.size());; ++n) {
    path = std::filesystem::path(options.screenshot_dir) / fmt::format("relief_{:04d}.png", n);
    if (!std::filesystem::exists(path)) break;
  }
  if (Status st = write_screenshot(path.string()); !st) {
    std::fprintf(stderr, "relief: %s\n", st.error().message.c_str());
  }
}

Result<std::unique_ptr<Viewer>> Viewer::create(Window& window, const tiles::Store* elevation,
                                               const tiles::Store* imagery,
                                               const view::SceneOptions& scene,
                                               const ViewerOptions& options, const Clock& clock) {
  auto impl = std::make_unique<Impl>(window, elevation, imagery, scene, options, clock);
  impl->imagery_on = impl->imagery_wanted = imagery != nullptr;
  impl->panels = options.panels;
  impl->recording = options.record;
  impl->threshold = scene.selection.pixel_error;
  // Overlap: the scene's frames return once the GL has their draw calls.
  impl->scene_options.render.finish = !options.overlap;
  if (options.refine_threads_auto && options.overlap && window.software_renderer()) {
    impl->scene_options.refine_threads = 1;
  }
  RELIEF_CHECK(impl->make_scene());
  lod::Camera start = options.start;
  start.width = window.target().width();
  start.height_px = window.target().height();
  impl->controller = view::make_controller(options.mode, start, options.controller);
  std::unique_ptr<Viewer> v(new Viewer(std::move(impl)));
  window.set_input_handler(
      [impl = v->impl_.get()](const view::InputEvent& e) { impl->on_input(e); });
  return v;
}

Viewer::Viewer(std::unique_ptr<Impl> impl) : impl_(std::move(impl)) {}

Viewer::~Viewer() {
  if (!impl_) return;
  impl_->window.set_input_handler({});
  if (impl_->export_job.valid()) impl_->export_job.wait();  // it uses the stores
}

Result<bool> Viewer::frame() {
  using Idle = Impl::Idle;
  Impl& v = *impl_;
  const Clock::TimePoint entered = v.clock.now();
  if (v.idle != Idle::no) {
    // Cleared before the wait: a change from now on posts an event, one
    // posted before is still pending; either ends the wait.
    v.wakeup->posted = false;
    v.window.wait_events(v.options.idle_wait_seconds);
  } else {
    v.window.poll_events();
  }
  v.poll_export();
  if (v.quit || v.window.should_close()) {
    v.window.swap_pending();
    return false;
  }
  const Clock::TimePoint now = v.clock.now();
  if (v.idle != Idle::no) {
    v.waited += seconds_between(entered, now);
    // Waiting for tiles: a change in the scene draws, and so does the
    // timeout on the clock (a failed tile is asked for again by a frame).
    const bool woken = v.idle == Idle::waiting &&
                       (v.wakeup->changes != v.drawn_changes ||
                        seconds_between(v.drawn_start, now) >= v.options.idle_wait_seconds);
    if (!woken && v.window.events() == v.drawn_events && v.export_status == v.drawn_export_status) {
      v.last = now;  // time passes without frames: the next step starts from here
      v.time = seconds_between(*v.start, now);
      ++v.skipped;
      return true;
    }
  }
  // A frame after events draws, and so does the next: Dear ImGui shows the
  // effect of some input (hover, a release) one frame later.
  const bool quiet = v.window.events() == v.drawn_events;
  if (!v.start) v.start = v.last = now;
  const double dt = seconds_between(*v.last, now);
  const double cpu = static_cast<double>(std::clock()) / CLOCKS_PER_SEC;
  if (v.index > 0) {
    // The previous frame's period, from its start to this one's, known now:
    // its frame time (idle waits between them left out).
    const double period_ms = (seconds_between(v.drawn_start, now) - v.waited) * 1e3;
    v.frame_ms.push_back(period_ms);
    v.last_frame_ms = period_ms;
    v.recent_ms.push_back(period_ms);
    if (v.recent_ms.size() > kRecentFrames) v.recent_ms.pop_front();
    if (v.options.collect_frames) {
      v.frames.back().frame_ms = period_ms;
      v.frames.back().process_cpu_ms = (cpu - v.last_cpu) * 1e3;
    }
  }
  v.last = v.drawn_start = now;
  v.last_cpu = cpu;
  v.waited = 0;
  v.drawn_changes = v.wakeup->changes;  // what arrives from now on draws again
  v.time = seconds_between(*v.start, now);
  if (v.imagery_wanted != v.imagery_on) {
    v.imagery_on = v.imagery_wanted;
    RELIEF_CHECK(v.make_scene());
  }

  const view::Ground ground = view::resident_ground(*v.scene);
  lod::Camera camera = v.controller->update(dt, ground);
  render::RenderTarget& target = v.window.target();
  camera.width = target.width();
  camera.height_px = target.height();
  v.move_dragged_lens(camera, ground);
  const double still = v.scene_options.selection.pixel_error;
  const double above = camera.height - ground(camera.lon, camera.lat).value_or(0.0);
  const double speed_threshold = v.speed_lod.threshold(
      still, dt, v.controller->angular_speed(), v.controller->linear_speed(), std::max(above, 1.0));
  // Moving: the controller's speeds, as the speed's relaxation sees them.
  const bool moving = v.controller->angular_speed() != 0 || v.controller->linear_speed() != 0;
  // The budget may tighten the speed's relaxation, never the still threshold.
  const double budget = v.frame_budget.update(v.last_frame_ms, dt, moving, still / speed_threshold);
  v.threshold = budget == 1 ? speed_threshold : std::max(still, speed_threshold * budget);
  v.scene->set_pixel_error(v.threshold);
  // The previous frame, if its swap was left to this one: swapped once this
  // frame's selection and refinement are made (they ran while the GL drew it).
  double swap_ms = 0;
  const auto swap_previous = [&] {
    const Clock::TimePoint swapping = v.clock.now();
    v.window.swap_pending();
    swap_ms = seconds_between(swapping, v.clock.now()) * 1e3;
  };
  const view::FrameReport report = RELIEF_TRY(v.scene->draw(camera, target, swap_previous));
  v.report = report;
  if (v.recording) v.record(camera);
  const bool playing =
      v.controller->mode() == view::ControlMode::playback && !v.controller->finished();
  // Still: nothing moved, nothing came in, nothing is recorded or played.
  // Then a complete frame (or a frozen selection) is drawn again only for an
  // event; an incomplete one also when the scene's loads (or detections)
  // bring something new, unless the next frame draws more anyway (or the
  // threshold is still relaxed after the motion).
  const bool at_rest = v.options.idle_wait_seconds > 0 && quiet && !v.recording && !playing &&
                       v.drawn_camera && same_camera(*v.drawn_camera, camera);
  const bool relaxed = v.threshold > still;
  if (at_rest && ((report.complete && !relaxed) || v.frozen)) {
    v.idle = Idle::complete;
  } else if (at_rest && !relaxed && !report.draws_more) {
    v.idle = Idle::waiting;
  } else {
    v.idle = Idle::no;
  }
  v.drawn_camera = camera;

  if (v.options.collect_frames) {
    // frame_ms and process_cpu_ms: once the next frame starts.
    v.frames.push_back({v.index, v.time, 0.0, report.frame_seconds * 1e3, v.threshold, camera,
                        report.selection.quads, report.draw.triangles,
                        report.draw.triangles_per_pixel(),
                        report.draw.geometry_bytes + report.draw.texture_bytes, report.complete});
    ViewerFrame& f = v.frames.back();
    f.speed_factor = v.speed_lod.factor();
    f.budget_factor = v.frame_budget.factor();
    f.select_ms = report.select_seconds * 1e3;
    f.page_faults = report.page_faults;
    f.prepare_ms = report.draw.prepare_seconds * 1e3;
    f.gpu_ms = report.draw.gpu_seconds * 1e3;
    f.submit_ms = report.draw.submit_seconds * 1e3;
    f.tiles_uploaded = report.draw.uploads;
    f.uploads_deferred = report.selection.deferred;
    f.cached_bytes = report.cached_bytes;
    if (report.refine) {
      f.refine_ms = report.refine->seconds * 1e3;
      f.refine_cpu_ms = report.refine->cpu_seconds * 1e3;
      f.marks_evaluated = report.refine->marks_evaluated;
      f.criteria_ms = report.refine->criteria_seconds * 1e3;
      f.marks_near = report.refine->marks_near;
      f.marks_reused = report.refine->marks_reused;
      f.quads_reused = report.refine->quads_reused;
      f.tiles_measured = report.refine->tiles_measured;
    }
  }
  if (stream::TileLoader* loader = v.scene->elevation_loader()) {
    const stream::LoaderStats s = loader->stats();
    v.progress.update(s);
    v.elevation_rate.update(v.time, s);
  }
  if (stream::TileLoader* loader = v.scene->imagery_loader()) {
    v.imagery_rate.update(v.time, loader->stats());
  }
  const Clock::TimePoint presenting = v.clock.now();
  // Left to the next frame only when that follows at once (no idle wait).
  const bool defer_swap = v.options.overlap && v.idle == Impl::Idle::no;
  if (v.panels) {
    v.pick = v.cursor_x >= 0 ? view::pick(camera, v.cursor_x, v.cursor_y, ground) : std::nullopt;
    v.window.present([&v] { draw_panels(v); }, defer_swap);
  } else {
    v.window.present({}, defer_swap);
  }
  if (v.options.collect_frames) {
    // The wait for the previous frame's swap (overlap), then this one's copy and panels.
    v.frames.back().swap_ms = swap_ms;
    v.frames.back().present_ms = seconds_between(presenting, v.clock.now()) * 1e3;
  }
  ++v.index;
  v.drawn_events = v.window.events();  // what the panels took while drawn included
  v.drawn_export_status = v.export_status;

  if (v.options.exit_when_done) {
    const bool path_done =
        v.controller->mode() != view::ControlMode::playback || v.controller->finished();
    if (path_done && !v.path_end) v.path_end = v.time;
    // Complete at the still threshold: a frame complete while the threshold
    // is still relaxed after the motion is coarser than the still.
    const bool done = report.complete && v.threshold <= still;
    if (path_done && (done || v.time - *v.path_end >= v.options.until_complete)) {
      v.window.swap_pending();
      return false;
    }
  }
  return true;
}

Result<ViewerSummary> Viewer::run() {
  while (RELIEF_TRY(frame())) {
  }
  return summary();
}

ViewerSummary Viewer::summary() const {
  const Impl& v = *impl_;
  ViewerSummary s;
  s.frames = v.index;
  s.skipped_frames = v.skipped;
  s.seconds = v.time;
  s.p50_frame_ms = view::percentile(v.frame_ms, 0.5);
  s.p99_frame_ms = view::percentile(v.frame_ms, 0.99);
  s.complete =
      v.report && v.report->complete && v.threshold <= v.scene_options.selection.pixel_error;
  s.path_finished = v.controller->mode() == view::ControlMode::playback && v.controller->finished();
  s.path_end = v.path_end;
  s.frames_list = v.frames;
  s.recorded = v.recorded;
  s.screenshots = v.screenshots;
  for (const auto& [key, error] : v.unreadable) s.unreadable_tiles.push_back(error);
  return s;
}

view::Controller& Viewer::controller() {
  return *impl_->controller;
}

void Viewer::set_controller(std::unique_ptr<view::Controller> controller) {
  impl_->controller = std::move(controller);
}

view::Scene& Viewer::scene() {
  return *impl_->scene;
}

bool Viewer::panels_visible() const {
  return impl_->panels;
}

bool Viewer::recording() const {
  return impl_->recording;
}

bool Viewer::export_recorded() {
  return impl_->export_recorded();
}

Status Viewer::wait_for_export() {
  Impl& v = *impl_;
  if (!v.export_job.valid()) return {};
  const Status st = v.export_job.get();
  v.export_status = st ? "exported" : "export failed: " + st.error().message;
  return st;
}

Status Viewer::screenshot(const std::string& path) {
  return impl_->write_screenshot(path);
}

}  // namespace relief::window
