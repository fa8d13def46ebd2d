// The viewer's window under Xvfb (the CTest runs this binary through
// xvfb-run): it opens and draws; input delivered the way GLFW's callbacks
// deliver it reaches the controller, except the keys the viewer keeps; a
// window frame equals the headless still of its camera; scripted sessions
// (--play --exit-when-done --stats, --record) run without input; bad input is
// a one-line error.
#include <gtest/gtest.h>

#include <chrono>
#include <cmath>
#include <fstream>
#include <limits>
#include <thread>

#include <fmt/format.h>
#include <nlohmann/json.hpp>

#include "../ingest/built_stores.h"
#include "../support/images.h"
#include "../support/test_support.h"
#include "../video/movie_probe.h"
#include "glfw_input.h"
#include "pyrenees_view.h"
#include "relief/base/manual_clock.h"
#include "relief/lod/vec.h"
#include "relief/stream/throttled_source.h"
#include "relief/view/ground.h"
#include "relief/view/lens_drag.h"
#include "relief/window/viewer.h"
#include "relief/window/window.h"

namespace relief::window {
namespace {

using namespace std::chrono_literals;
using nlohmann::json;
using testing::kNoMesaLeakReport;
using testing::run_relief;
using testing::ScratchDir;
using Type = view::InputEvent::Type;

const lod::Camera kCamera = lod::look_at(1.5, 42.5, 1500, 30000, 20, -35, 60, kWidth, kHeight);

// A controller that notes what reaches it and passes it on.
class NotingController final : public view::Controller {
 public:
  explicit NotingController(std::unique_ptr<view::Controller> inner) : inner_(std::move(inner)) {}
  view::ControlMode mode() const override { return inner_->mode(); }
  void push(const view::InputEvent& e) override {
    pushed.push_back(e);
    inner_->push(e);
  }
  const lod::Camera& update(double dt, const view::Ground& ground) override {
    updates.push_back({dt, pushed.size()});
    return inner_->update(dt, ground);
  }
  const lod::Camera& camera() const override { return inner_->camera(); }
  void set_camera(const lod::Camera& c) override { inner_->set_camera(c); }
  double linear_speed() const override { return inner_->linear_speed(); }
  double angular_speed() const override { return inner_->angular_speed(); }

  std::vector<view::InputEvent> pushed;
  std::vector<std::pair<double, size_t>> updates;  // dt, events pushed before the update

 private:
  std::unique_ptr<view::Controller> inner_;
};

class WindowTest : public ::testing::Test {
 protected:
  void SetUp() override {
    WindowOptions o;
    o.width = kWidth, o.height = kHeight, o.vsync = false;
    auto w = Window::create(o);
    ASSERT_TRUE(w) << w.error().message;
    window_ = std::move(*w);
  }

  std::unique_ptr<Viewer> viewer(const ViewerOptions& o, const Clock& clock) {
    view::SceneOptions so;
    so.mesh_level = 3;
    so.refine_threads = 0;  // one per core, unless the viewer chooses
    auto v = Viewer::create(*window_, &testing::pyrenees_store(), nullptr, so, o, clock);
    EXPECT_TRUE(v) << v.error().message;
    return v ? std::move(*v) : nullptr;
  }

  std::unique_ptr<Window> window_;
};

TEST_F(WindowTest, OpensAndDrawsTheTerrainUntilTheViewIsComplete) {
  EXPECT_EQ(window_->target().width(), kWidth);
  EXPECT_EQ(window_->target().height(), kHeight);
  ViewerOptions o;
  o.start = kCamera;
  o.exit_when_done = true;
  o.until_complete = 120;
  auto v = viewer(o, steady_clock());
  ASSERT_TRUE(v);
  auto summary = v->run();
  ASSERT_TRUE(summary) << summary.error().message;
  EXPECT_TRUE(summary->complete);
  EXPECT_GE(summary->frames, 1u);
  auto pixels = window_->target().read_rgba();
  ASSERT_TRUE(pixels);
  const testing::Image image{kWidth, kHeight, *pixels};
  const uint8_t* sky = image.rgba.data();  // the top left corner shows the sky
  const auto sky_pixels = testing::count_colour(image, sky[0], sky[1], sky[2]);
  EXPECT_LT(sky_pixels, size_t{kWidth} * kHeight / 2) << "the terrain fills the lower half";
}

TEST_F(WindowTest, DeliveredInputReachesTheControllerAtTheNextFrame) {
  ManualClock clock;
  ViewerOptions o;
  o.start = kCamera;
  auto v = viewer(o, clock);
  ASSERT_TRUE(v);
  auto noting =
      std::make_unique<NotingController>(view::make_controller(view::ControlMode::orbit, kCamera));
  NotingController& c = *noting;
  v->set_controller(std::move(noting));

  auto key = [](Type t, view::Key k) {
    view::InputEvent e;
    e.type = t, e.key = k;
    return e;
  };
  view::InputEvent cursor;
  cursor.type = Type::cursor, cursor.x = 100, cursor.y = 80;
  view::InputEvent scroll;
  scroll.type = Type::scroll, scroll.y = -2;
  // The same entry point GLFW's callbacks use.
  window_->deliver(key(Type::key_down, view::Key::w));
  window_->deliver(cursor);
  window_->deliver(scroll);
  window_->deliver(key(Type::key_down, view::Key::tab));  // the viewer's: panels off
  window_->deliver(key(Type::key_up, view::Key::tab));
  window_->deliver(key(Type::key_up, view::Key::w));
  clock.advance(50ms);
  ASSERT_TRUE(v->frame());
  clock.advance(50ms);
  ASSERT_TRUE(v->frame());

  ASSERT_EQ(c.pushed.size(), 4u);
  EXPECT_EQ(c.pushed[0].type, Type::key_down);
  EXPECT_EQ(c.pushed[0].key, view::Key::w);
  EXPECT_EQ(c.pushed[1].type, Type::cursor);
  EXPECT_EQ(c.pushed[1].x, 100);
  EXPECT_EQ(c.pushed[2].type, Type::scroll);
  EXPECT_EQ(c.pushed[2].y, -2);
  EXPECT_EQ(c.pushed[3].type, Type::key_up);
  EXPECT_FALSE(v->panels_visible());
  // Both frames updated the controller, the first after every event, with
  // the clock's time since the previous frame.
  ASSERT_EQ(c.updates.size(), 2u);
  EXPECT_EQ(c.updates[0], std::make_pair(0.0, size_t{4}));
  EXPECT_DOUBLE_EQ(c.updates[1].first, 0.05);

  // A resize reaches the controller and resizes the frames.
  view::InputEvent resize;
  resize.type = Type::resize, resize.x = 200, resize.y = 100;
  window_->deliver(resize);
  EXPECT_EQ(window_->target().width(), 200);
  EXPECT_EQ(window_->target().height(), 100);
  ASSERT_EQ(c.pushed.size(), 5u);
  EXPECT_EQ(c.pushed[4].type, Type::resize);
}

TEST_F(WindowTest, TheViewerKeysScreenshotRecordSwitchVsyncAndFullscreenAndQuit) {
  ScratchDir dir("window_keys");
  ManualClock clock;
  ViewerOptions o;
  o.start = kCamera;
  o.screenshot_dir = dir.path().string();
  auto v = viewer(o, clock);
  ASSERT_TRUE(v);
  view::InputEvent e;
  e.type = Type::key_down;
  e.key = view::Key::f9;  // recording on
  window_->deliver(e);
  EXPECT_TRUE(v->recording());
  for (int i = 0; i < 3; ++i) {
    ASSERT_TRUE(v->frame());
    clock.advance(100ms);
  }
  e.key = view::Key::f12;
  window_->deliver(e);
  window_->deliver(e);
  const ViewerSummary s = v->summary();
  ASSERT_EQ(s.screenshots.size(), 2u);
  EXPECT_EQ(s.screenshots[0], (dir / "relief_0000.png").string());
  EXPECT_EQ(s.screenshots[1], (dir / "relief_0001.png").string());
  const testing::Image shot = testing::read_png(s.screenshots[1], kWidth, kHeight);
  EXPECT_EQ(shot.width, kWidth);
  ASSERT_EQ(s.recorded.size(), 3u);
  EXPECT_DOUBLE_EQ(s.recorded[2].time, 0.2);
  EXPECT_EQ(s.recorded[2].camera.lon, kCamera.lon);

  const bool vsync = window_->vsync();
  e.key = view::Key::f8;
  window_->deliver(e);
  EXPECT_NE(window_->vsync(), vsync);
  // Fullscreen on the X server's screen, and back; frames follow the size.
  e.key = view::Key::f11;
  window_->deliver(e);
  EXPECT_TRUE(window_->fullscreen());
  // The X server answers asynchronously: a few frames at most.
  auto frames_until_width = [&](int width) {
    for (int i = 0; i < 50 && window_->target().width() != width; ++i) {
      ASSERT_TRUE(v->frame());
      std::this_thread::sleep_for(10ms);
    }
  };
  frames_until_width(1280);
  EXPECT_EQ(window_->target().width(), 1280);
  EXPECT_EQ(window_->target().height(), 1024);
  window_->deliver(e);
  EXPECT_FALSE(window_->fullscreen());
  frames_until_width(kWidth);
  EXPECT_EQ(window_->target().width(), kWidth);
  EXPECT_EQ(window_->target().height(), kHeight);

  e.key = view::Key::escape;
  window_->deliver(e);
  EXPECT_FALSE(*v->frame());
}

// F10 ("export recorded path") hands the path recorded so far to the export
// function on a thread of its own; nothing recorded, nothing exported; an
// export's failure comes back from wait_for_export().
TEST_F(WindowTest, F10ExportsTheRecordedPathOnAThreadOfItsOwn) {
  ManualClock clock;
  ViewerOptions o;
  o.start = kCamera;
  o.record_fps = 12;
  std::vector<view::PathFile> exported;
  bool fail_export = false;
  o.export_path = [&](const view::PathFile& path) -> Status {
    exported.push_back(path);
    if (fail_export) return fail("the disk is full");
    return {};
  };
  auto v = viewer(o, clock);
  ASSERT_TRUE(v);
  view::InputEvent e;
  e.type = Type::key_down;
  e.key = view::Key::f10;
  ASSERT_TRUE(v->frame());
  window_->deliver(e);  // nothing recorded yet
  EXPECT_TRUE(v->wait_for_export());
  EXPECT_TRUE(exported.empty());

  e.key = view::Key::f9;  // recording on
  window_->deliver(e);
  for (int i = 0; i < 3; ++i) {
    clock.advance(100ms);
    ASSERT_TRUE(v->frame());
  }
  e.key = view::Key::f10;
  window_->deliver(e);
  ASSERT_TRUE(v->wait_for_export());
  ASSERT_EQ(exported.size(), 1u);
  EXPECT_EQ(exported[0].fps, 12);
  ASSERT_EQ(exported[0].keyframes.size(), 3u);
  EXPECT_DOUBLE_EQ(exported[0].keyframes[2].time, 0.3);

  fail_export = true;
  EXPECT_TRUE(v->export_recorded());
  const Status st = v->wait_for_export();
  ASSERT_FALSE(st);
  EXPECT_EQ(st.error().message, "the disk is full");
  EXPECT_EQ(exported.size(), 2u);
}

// Idle: once the camera is still and its frame complete, frame() waits for
// events instead of drawing; an event draws one frame, then it idles again.
// Never while recording.
TEST_F(WindowTest, AStillCompleteViewIsNotRedrawnUntilAnEventComes) {
  ManualClock clock;
  ViewerOptions o;
  o.start = kCamera;
  o.idle_wait_seconds = 0.001;
  auto v = viewer(o, clock);
  ASSERT_TRUE(v);
  // Until complete: frames draw while tiles arrive.
  for (int i = 0; i < 6000 && v->summary().skipped_frames == 0; ++i) {
    ASSERT_TRUE(v->frame());
    clock.advance(10ms);
    std::this_thread::sleep_for(1ms);
  }
  ViewerSummary s = v->summary();
  ASSERT_GT(s.skipped_frames, 0u);
  EXPECT_TRUE(s.complete);
  const size_t drawn = s.frames;
  for (int i = 0; i < 20; ++i) {
    ASSERT_TRUE(v->frame());
    clock.advance(10ms);
  }
  s = v->summary();
  EXPECT_EQ(s.frames, drawn) << "nothing changed: nothing drawn";
  EXPECT_EQ(s.skipped_frames, 21u);
  EXPECT_DOUBLE_EQ(s.seconds, v->summary().seconds);

  // The cursor moves: two frames (the panels show some input a frame
  // late), then idle again.
  view::InputEvent e;
  e.type = Type::cursor;
  e.x = 10, e.y = 10;
  window_->deliver(e);
  for (int i = 0; i < 3; ++i) ASSERT_TRUE(v->frame());
  s = v->summary();
  EXPECT_EQ(s.frames, drawn + 2);
  EXPECT_EQ(s.skipped_frames, 22u);

  e.type = Type::key_down;  // recording: every frame is drawn (and recorded)
  e.key = view::Key::f9;
  window_->deliver(e);
  for (int i = 0; i < 5; ++i) {
    clock.advance(10ms);
    ASSERT_TRUE(v->frame());
  }
  s = v->summary();
  EXPECT_EQ(s.frames, drawn + 7);
  EXPECT_EQ(s.recorded.size(), 5u);
}

// Idle while waiting: a still view whose tiles have not arrived is not
// redrawn until one does. The Pyrenees store behind a link whose answers
// wait on a clock of the test's; the viewer's clock never moves, so neither
// the idle timeout nor the camera can draw a frame: only input, which there
// is none of, or a tile's arrival.
TEST_F(WindowTest, AStillViewWaitingForTilesIsRedrawnOnlyWhenOneArrives) {
  ManualClock clock, link_clock;
  stream::LinkModel link;
  link.latency = std::chrono::seconds(1);
  auto source = stream::throttled_source(tiles::local_source(testing::pyrenees_store().root()),
                                         link, link_clock);
  link_clock.set_free(true);  // the manifest, the indices and level 0 at once
  auto store = tiles::Store::open(source);
  ASSERT_TRUE(store) << store.error().message;
  ViewerOptions o;
  o.start = kCamera;
  o.idle_wait_seconds = 0.02;  // real time per wait; on the viewer's clock it never ends
  view::SceneOptions so;
  so.mesh_level = 3;
  auto created = Viewer::create(*window_, &*store, nullptr, so, o, clock);
  ASSERT_TRUE(created) << created.error().message;
  Viewer& v = **created;
  // Whatever happens, no load is left asleep on the link when the viewer goes.
  struct Free {
    ManualClock& clock;
    ~Free() { clock.set_free(true); }
  } free_link{link_clock};
  link_clock.set_free(false);
  stream::TileLoader& loader = *v.scene().elevation_loader();
  const uint64_t loaded_at_start = loader.stats().loaded;
  // The first frames ask for level 1 and draw level 0; the loads wait on the link.
  for (int i = 0; i < 50 && v.summary().skipped_frames == 0; ++i) ASSERT_TRUE(v.frame());
  ViewerSummary s = v.summary();
  ASSERT_EQ(s.skipped_frames, 1u) << "a still, incomplete view idles";
  EXPECT_FALSE(s.complete);
  ASSERT_TRUE(link_clock.wait_for_sleepers(1));
  const size_t drawn = s.frames;
  for (int i = 0; i < 20; ++i) ASSERT_TRUE(v.frame());
  s = v.summary();
  EXPECT_EQ(s.frames, drawn) << "no tile arrived: nothing drawn";
  EXPECT_EQ(s.skipped_frames, 21u);

  // The link answers: the loads that end wake the viewer, which draws.
  const uint64_t events = window_->events();
  link_clock.advance(std::chrono::seconds(1));
  for (int i = 0; i < 500 && v.summary().frames == drawn; ++i) ASSERT_TRUE(v.frame());
  EXPECT_EQ(v.summary().frames, drawn + 1) << "an arrival draws a frame";
  EXPECT_EQ(window_->events(), events) << "without input";
  EXPECT_GT(loader.stats().loaded, loaded_at_start);

  // Until complete, one frame per wake at most: never more frames than
  // loads that ended (each wake is one) and the frame after the last.
  link_clock.set_free(true);
  const uint64_t ended_before = loader.stats().loaded + loader.stats().failed;
  const size_t frames_before = v.summary().frames, skipped_before = v.summary().skipped_frames;
  for (int i = 0; i < 3000 && !v.summary().complete; ++i) ASSERT_TRUE(v.frame());
  s = v.summary();
  ASSERT_TRUE(s.complete);
  const uint64_t ended = loader.stats().loaded + loader.stats().failed - ended_before;
  EXPECT_LE(s.frames - frames_before, ended + 1);
  EXPECT_EQ(window_->events(), events);
  // Complete: no arrival (a late prefetch) draws it again.
  for (int i = 0; i < 5; ++i) ASSERT_TRUE(v.frame());
  EXPECT_EQ(v.summary().frames, s.frames);
  EXPECT_GT(v.summary().skipped_frames, skipped_before);
}

// Per-frame statistics: a frame's frame time is its own period, from its
// start to the next frame's start, known once that one starts (the last
// frame has none); the percentiles are over those periods.
TEST_F(WindowTest, AFramesTimeIsItsOwnPeriod) {
  ManualClock clock;
  ViewerOptions o;
  o.start = kCamera;
  o.collect_frames = true;
  o.idle_wait_seconds = 0;  // every call draws
  auto v = viewer(o, clock);
  ASSERT_TRUE(v);
  for (const auto period : {10ms, 30ms, 20ms}) {
    ASSERT_TRUE(v->frame());
    clock.advance(period);
  }
  ASSERT_TRUE(v->frame());
  const ViewerSummary s = v->summary();
  ASSERT_EQ(s.frames_list.size(), 4u);
  EXPECT_DOUBLE_EQ(s.frames_list[0].frame_ms, 10);
  EXPECT_DOUBLE_EQ(s.frames_list[1].frame_ms, 30);
  EXPECT_DOUBLE_EQ(s.frames_list[2].frame_ms, 20);
  EXPECT_DOUBLE_EQ(s.frames_list[3].frame_ms, 0);
  EXPECT_DOUBLE_EQ(s.frames_list[2].time, 0.04);
  EXPECT_DOUBLE_EQ(s.p50_frame_ms, 20);
  EXPECT_DOUBLE_EQ(s.p99_frame_ms, 30);
}

// A path of `seconds` played with a 30 fps budget, every frame `frame` long
// on the test's clock, until the view is complete and `frames` have run.
// The tiles load in real time while the frames run back to back: after
// `frames`, each frame leaves the loaders a moment (under ASan on a busy
// machine they took more than 40 frames). The deadline only guards a hang.
class FrameBudgetWindowTest : public WindowTest {
 protected:
  void fly(double seconds, std::chrono::milliseconds frame, int frames, ViewerSummary& out) {
    ManualClock clock;
    ViewerOptions o;
    o.mode = view::ControlMode::playback;
    lod::Camera end = kCamera;
    end.lon += 0.05, end.heading += 30;
    o.controller.path = {{0, kCamera}, {seconds, end}};
    o.start = kCamera;
    o.frame_budget.target_ms = 1000.0 / 30;
    o.collect_frames = true;
    o.idle_wait_seconds = 0;
    auto v = viewer(o, clock);
    ASSERT_TRUE(v);
    const auto deadline = std::chrono::steady_clock::now() + 300s;
    for (int i = 0; !(i > frames && v->summary().complete); ++i) {
      ASSERT_LT(std::chrono::steady_clock::now(), deadline)
          << "not complete after " << i << " frames";
      ASSERT_TRUE(v->frame());
      clock.advance(frame);
      if (i > frames) std::this_thread::sleep_for(10ms);
    }
    out = v->summary();
    // Once the path has ended the threshold is the still one, exactly.
    EXPECT_EQ(out.frames_list.back().budget_factor, 1);
    EXPECT_EQ(out.frames_list.back().pixel_error, 1);
    EXPECT_TRUE(out.complete);
  }
};

// Frames three times over the budget while a path plays relax the
// threshold beyond the speed's, by at most x1.3 a frame and x3 in all.
TEST_F(FrameBudgetWindowTest, FramesOverTheirBudgetCoarsenAMovingViewButNotTheStillOne) {
  ViewerSummary s;
  ASSERT_NO_FATAL_FAILURE(fly(1, 100ms, 20, s));
  ASSERT_GE(s.frames_list.size(), 12u);
  double previous = 1;
  for (size_t i = 1; i < 10; ++i) {  // moving (the path's second), every frame 100 ms
    const ViewerFrame& f = s.frames_list[i];
    EXPECT_GT(f.budget_factor, 1) << i;
    EXPECT_LE(f.budget_factor, std::min(3.0, previous * 1.3) + 1e-12) << i;
    EXPECT_GT(f.speed_factor, 1) << i;
    EXPECT_NEAR(f.pixel_error, f.speed_factor * f.budget_factor, 1e-12) << i;
    previous = f.budget_factor;
  }
  EXPECT_EQ(previous, 3);
}

// Frames well within the budget while the path plays tighten the speed's
// relaxation (the time is there for detail), never below the still
// threshold.
TEST_F(FrameBudgetWindowTest, FramesWithinTheirBudgetTightenTheSpeedsRelaxationNotTheStill) {
  ViewerSummary s;
  ASSERT_NO_FATAL_FAILURE(fly(0.5, 10ms, 60, s));  // 10 ms frames: well within 33 ms
  ASSERT_GE(s.frames_list.size(), 50u);
  double previous = 1;
  int tighter = 0;
  for (size_t i = 1; i < 45; ++i) {  // moving (the path's half second)
    const ViewerFrame& f = s.frames_list[i];
    EXPECT_GT(f.speed_factor, 1) << i;
    EXPECT_LE(f.budget_factor, previous) << i;
    EXPECT_GE(f.pixel_error, 1) << i;  // the still threshold
    EXPECT_LE(f.pixel_error, f.speed_factor + 1e-12) << i;
    tighter += f.pixel_error < f.speed_factor - 1e-9;
    previous = f.budget_factor;
  }
  EXPECT_GT(tighter, 30);
  EXPECT_LT(previous, 1);
}

// GLFW reports the cursor in window coordinates; frames and picking use
// framebuffer pixels, twice as many per axis at a content scale of 2.
TEST(WindowInput, CursorPositionsAreScaledToFramebufferPixels) {
  EXPECT_EQ(cursor_to_pixels(100, 50, 640, 360, 1280, 720), std::make_pair(200.0, 100.0));
  EXPECT_EQ(cursor_to_pixels(100, 50, 640, 360, 640, 360), std::make_pair(100.0, 50.0));
  EXPECT_EQ(cursor_to_pixels(10, 10, 400, 200, 600, 400), std::make_pair(15.0, 20.0));
  EXPECT_EQ(cursor_to_pixels(7, 9, 0, 0, 0, 0), std::make_pair(7.0, 9.0));  // minimised
}

size_t differing_pixels(const std::vector<uint8_t>& a, const std::vector<uint8_t>& b) {
  size_t n = 0;
  for (size_t i = 0; i + 3 < std::min(a.size(), b.size()); i += 4) {
    n += !std::equal(&a[i], &a[i + 3], &b[i]);
  }
  return n;
}

// Overlap (docs/viewer.md): while frames follow one another (the camera
// moves), each frame's swap is left to the next, which swaps it once its own
// selection and refinement are made; quitting swaps what is left. Without
// overlap every frame is swapped before frame() returns.
TEST_F(WindowTest, WhileFramesFollowEachOtherEachIsSwappedByTheNext) {
  view::InputEvent pan;
  pan.type = Type::key_down, pan.key = view::Key::w;
  view::InputEvent escape;
  escape.type = Type::key_down, escape.key = view::Key::escape;
  for (const bool overlap : {true, false}) {
    SCOPED_TRACE(overlap ? "overlap" : "no overlap");
    ManualClock clock;
    ViewerOptions o;
    o.start = kCamera;
    o.panels = false;
    o.overlap = overlap;
    auto v = viewer(o, clock);
    ASSERT_TRUE(v);
    window_->deliver(pan);  // held: the camera moves every frame
    const uint64_t swaps = window_->swaps();
    for (uint64_t frame = 1; frame <= 3; ++frame) {
      clock.advance(100ms);
      ASSERT_TRUE(v->frame());
      EXPECT_EQ(window_->swaps() - swaps, overlap ? frame - 1 : frame);
      EXPECT_EQ(window_->swap_is_pending(), overlap);
    }
    window_->deliver(escape);
    auto more = v->frame();
    ASSERT_TRUE(more);
    EXPECT_FALSE(*more);
    EXPECT_EQ(window_->swaps() - swaps, 3u);
    EXPECT_FALSE(window_->swap_is_pending());
  }
}

// Xvfb's GL is llvmpipe: the viewer left to choose refines on the render
// thread alone while frames overlap, and keeps what it was given otherwise.
TEST_F(WindowTest, OnASoftwareRasteriserTheViewerRefinesOnTheRenderThreadAlone) {
  ASSERT_TRUE(window_->software_renderer()) << window_->renderer();
  struct Case {
    bool automatic, overlap;
    unsigned threads;
  };
  for (const Case c : {Case{true, true, 1}, Case{false, true, 0}, Case{true, false, 0}}) {
    ViewerOptions o;
    o.start = kCamera;
    o.refine_threads_auto = c.automatic;
    o.overlap = c.overlap;
    auto v = viewer(o, steady_clock());
    ASSERT_TRUE(v);
    EXPECT_EQ(v->scene().options().refine_threads, c.threads) << c.automatic << c.overlap;
  }
}

TEST_F(WindowTest, PanelsAreDrawnOverTheFrameButNotInScreenshots) {
  ManualClock clock;
  ViewerOptions o;
  o.start = kCamera;
  auto v = viewer(o, clock);
  ASSERT_TRUE(v);
  window_->set_keep_screen(true);
  ASSERT_TRUE(v->frame());  // Dear ImGui sizes auto-resized panels in their first frame
  clock.advance(100ms);
  ASSERT_TRUE(v->frame());
  window_->swap_pending();  // overlap: else the next frame swaps this one
  auto frame = window_->target().read_rgba();
  const std::vector<uint8_t>* screen = &window_->screen();
  ASSERT_TRUE(frame);
  ASSERT_EQ(screen->size(), frame->size());
  EXPECT_GT(differing_pixels(*frame, *screen), size_t{1000})
      << "the panels cover part of the frame";

  view::InputEvent tab;
  tab.type = Type::key_down, tab.key = view::Key::tab;
  window_->deliver(tab);
  clock.advance(100ms);
  ASSERT_TRUE(v->frame());
  window_->swap_pending();
  frame = window_->target().read_rgba();
  ASSERT_TRUE(frame);
  EXPECT_EQ(differing_pixels(*frame, *screen), 0u) << "without panels the screen is the frame";
}

// A lens of a texture layer (the Pyrenees heights as a single-band layer, a
// mean filter inside a 3 km circle) is grabbed by a left press inside its
// circle and follows the terrain point under the cursor: after the release
// its centre is the point picked under the release position (within 1 m: the
// same pick, on the same resident ground, from the same camera, which the
// drag leaves alone). A drag starting outside every lens, or inside one with
// Control held, still turns the view and leaves the lens where it is.
TEST_F(WindowTest, ALensIsDraggedOnTheTerrainWhileOtherDragsStillTurnTheView) {
  ManualClock clock;
  ViewerOptions o;
  o.start = kCamera;
  o.collect_frames = true;
  o.idle_wait_seconds = 0;
  o.panels = false;
  view::SceneOptions so;
  so.mesh_level = 3;
  // Frames stepped deterministically: no wall-clock budget on processing.
  so.render.processing_per_frame = std::numeric_limits<double>::infinity();
  render::TextureLayer layer;
  layer.store = &testing::pyrenees_store();
  layer.range_max = 3000;
  auto mean = gpuprocess::make_step("mean", {"radius=2"});
  ASSERT_TRUE(mean) << mean.error().message;
  layer.lenses.push_back({1.5, 42.5, 3000, {{*mean}}});
  so.texture_layers = {layer};
  so.selection.texture = layer.store;
  auto created = Viewer::create(*window_, &testing::pyrenees_store(), nullptr, so, o, clock);
  ASSERT_TRUE(created) << created.error().message;
  Viewer& v = **created;
  for (int i = 0; i < 6000 && !v.summary().complete; ++i) {
    clock.advance(10ms);
    ASSERT_TRUE(v.frame());
    std::this_thread::sleep_for(1ms);
  }
  ASSERT_TRUE(v.summary().complete);
  const lod::Camera camera = v.summary().frames_list.back().camera;
  auto lens = [&v] { return v.scene().options().texture_layers[0].lenses[0]; };
  auto pick = [&](const lod::Camera& c, double x, double y) {
    auto p = view::pick(c, x, y, view::resident_ground(v.scene()));
    EXPECT_TRUE(p) << x << ", " << y << " shows the sky";
    return p.value_or(view::Pick{});
  };
  auto inside = [&](const lod::Camera& c, double x, double y) {
    const view::Pick p = pick(c, x, y);
    return view::lens_at(v.scene().options().texture_layers, p.lon, p.lat).has_value();
  };
  // Where the lens centre shows.
  auto centre_on_screen = [&](const lod::Camera& c) {
    auto view = lod::make_view(c);
    EXPECT_TRUE(view);
    const render::Lens l = lens();
    const double h = view::resident_ground(v.scene())(l.lon, l.lat).value_or(0.0);
    double x = -1, y = -1;
    EXPECT_TRUE(view && view->project(lod::ecef(l.lon, l.lat, h), x, y));
    return std::pair{x, y};
  };
  auto deliver = [&](Type type, double x, double y, uint8_t modifiers = 0) {
    view::InputEvent e;
    e.type = type, e.x = x, e.y = y, e.modifiers = modifiers;
    window_->deliver(e);
  };
  auto step = [&] {
    clock.advance(10ms);
    ASSERT_TRUE(v.frame());
  };
  auto last_camera = [&v] { return v.summary().frames_list.back().camera; };
  auto same_camera = [](const lod::Camera& a, const lod::Camera& b) {
    return a.lon == b.lon && a.lat == b.lat && a.height == b.height && a.heading == b.heading &&
           a.pitch == b.pitch && a.roll == b.roll;
  };
  const auto [cx, cy] = centre_on_screen(camera);
  ASSERT_TRUE(inside(camera, cx, cy));

  // The drag: the lens follows the cursor at each frame.
  deliver(Type::cursor, cx, cy);
  deliver(Type::mouse_down, cx, cy);
  step();
  deliver(Type::cursor, cx + 30, cy + 20);
  step();
  view::Pick at = pick(camera, cx + 30, cy + 20);
  EXPECT_LT(view::lens_distance_m(at.lon, at.lat, lens().lon, lens().lat), 1.0);
  deliver(Type::cursor, cx + 60, cy + 40);
  deliver(Type::mouse_up, cx + 60, cy + 40);
  step();
  at = pick(camera, cx + 60, cy + 40);
  EXPECT_LT(view::lens_distance_m(at.lon, at.lat, lens().lon, lens().lat), 1.0);
  EXPECT_GT(view::lens_distance_m(1.5, 42.5, lens().lon, lens().lat), 3000.0) << "it moved";
  EXPECT_TRUE(same_camera(camera, last_camera())) << "the drag left the camera alone";
  // Released: cursor moves no longer move it.
  const render::Lens dropped = lens();
  deliver(Type::cursor, cx - 40, cy);
  step();
  EXPECT_EQ(lens().lon, dropped.lon);
  EXPECT_EQ(lens().lat, dropped.lat);

  // Inside the lens with Control held, and outside every lens, a drag turns
  // the view about the point under the cursor as before (orbit: 40 px to the
  // right turn it 10 degrees).
  for (const uint8_t modifiers : {uint8_t{view::kControl}, uint8_t{0}}) {
    const lod::Camera before = last_camera();
    auto [x, y] = centre_on_screen(before);
    if (!modifiers) x -= 120;  // well outside the 3 km circle (~20 px in radius here)
    ASSERT_EQ(inside(before, x, y), modifiers != 0) << x << ", " << y;
    deliver(Type::cursor, x, y);
    deliver(Type::mouse_down, x, y, modifiers);
    deliver(Type::cursor, x + 40, y, modifiers);
    deliver(Type::mouse_up, x + 40, y, modifiers);
    step();
    EXPECT_NEAR(std::remainder(last_camera().heading - before.heading, 360.0), -10.0, 0.5)
        << int{modifiers};
    EXPECT_EQ(lens().lon, dropped.lon);
    EXPECT_EQ(lens().lat, dropped.lat);
  }
}

}  // namespace
}  // namespace relief::window
