#include "render_parallel.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <csignal>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <thread>

#include <fmt/format.h>
#include <nlohmann/json.hpp>

#include "commands.h"
#include "relief/lod/camera_path.h"
#include "relief/parallel/comm.h"
#include "relief/parallel/composite.h"
#include "relief/parallel/decompose.h"
#include "relief/parallel/frame_renderer.h"
#include "relief/parallel/wall.h"
#include "relief/view/path_file.h"
#include "render_setup.h"

namespace relief::cli {

namespace {

using Clock = std::chrono::steady_clock;
using parallel::Comm;
using parallel::ParallelMode;

// What rank 0 broadcasts for a frame: compact, fixed size.
struct FrameState {
  int32_t ok = 0;  // kFailed: rank 0 failed, every rank stops; kFrame: draw it; kEnd: done
  int32_t width = 0, height = 0;
  int32_t index = 0;  // of the frame in a path
  double lon = 0, lat = 0, height_m = 0, heading = 0, pitch = 0, roll = 0, fov_y = 60;
};

constexpr int32_t kFailed = 0, kFrame = 1, kEnd = 2;

FrameState state_of(const lod::Camera& c, int32_t index) {
  FrameState s;
  s.ok = kFrame, s.width = c.width, s.height = c.height_px, s.index = index;
  s.lon = c.lon, s.lat = c.lat, s.height_m = c.height, s.heading = c.heading, s.pitch = c.pitch;
  s.roll = c.roll, s.fov_y = c.fov_y;
  return s;
}

lod::Camera camera_of(const FrameState& s) {
  lod::Camera c;
  c.lon = s.lon, c.lat = s.lat, c.height = s.height_m, c.heading = s.heading;
  c.pitch = s.pitch, c.roll = s.roll, c.fov_y = s.fov_y, c.width = s.width;
  c.height_px = s.height;
  return c;
}

// Per-rank figures, gathered on rank 0 for --stats.
struct RankStats {
  uint64_t quads = 0, triangles = 0, bytes_sent = 0;
  double select_ms = 0, render_ms = 0, composite_ms = 0;
};

double ms_since(Clock::time_point t) {
  return std::chrono::duration<double, std::milli>(Clock::now() - t).count();
}

// Fault injection for the tests (RELIEF_PARALLEL_FAULT=kill:R or hang:R):
// rank R dies, or stops answering, before it sends its part of the frame.
void inject_fault(int rank) {
  const char* fault = std::getenv("RELIEF_PARALLEL_FAULT");
  if (!fault) return;
  const std::string f = fault;
  if (f == fmt::format("kill:{}", rank)) std::raise(SIGKILL);
  if (f == fmt::format("hang:{}", rank)) {
    for (;;) std::this_thread::sleep_for(std::chrono::seconds(1));
  }
}

// `out` with _rROW_cCOLUMN before its extension (a wall display's image).
std::string display_file(const std::string& out, const parallel::Wall& wall, int index) {
  const std::filesystem::path p(out);
  const std::string name = fmt::format("{}_r{}_c{}{}", p.stem().string(), index / wall.columns,
                                       index % wall.columns, p.extension().string());
  return (p.parent_path() / name).string();
}

class Run {
 public:
  Run(const Args& args, const ParallelMode& mode, const parallel::Compositing& compositing,
      Comm& comm)
      : args_(args), mode_(mode), compositing_(compositing), comm_(comm) {}

  int run() {
    // Errors every rank meets alike (arguments, store, wall file): rank 0
    // says it, every rank stops.
    auto setup = parse_render_setup(args_);
    if (!setup) return same_everywhere(setup.error().message);
    if (mode_.kind == ParallelMode::Kind::wall) {
      auto wall = parallel::read_wall(mode_.wall_file);
      if (!wall) return same_everywhere("--parallel: " + wall.error().message);
      if (wall->displays() != comm_.size()) {
        return same_everywhere(fmt::format("--parallel: {} has {} displays for {} ranks",
                                           mode_.wall_file, wall->displays(), comm_.size()));
      }
      if (args_.get("--size")) {
        return same_everywhere("--parallel: a wall's size comes from its file, not --size");
      }
      setup->width = wall->virtual_width();
      setup->height = wall->virtual_height();
      wall_ = *wall;
    }
    if (mode_.kind == ParallelMode::Kind::sort_first) {
      if (auto st = check_screen_tiles(setup->width, setup->height); !st) {
        return same_everywhere(st.error().message);
      }
    }
    const bool path = args_.get("--path").has_value();
    if (!path && !args_.get("--camera") == !args_.get("--look-at")) {
      return same_everywhere("render: give exactly one of --camera and --look-at");
    }
    // Rank 0 holds the cameras (a still's, or a path's frames) and sends
    // each frame's state to everyone.
    std::vector<lod::Camera> cameras;
    if (comm_.rank() == 0) {
      auto made = path ? path_cameras(*setup) : still_camera(*setup);
      if (made) {
        cameras = std::move(*made);
      } else {
        error_ = made.error().message;
      }
    }
    auto renderer = start(*setup);
    for (size_t i = 0;; ++i) {
      FrameState state;
      if (comm_.rank() == 0) {
        if (!error_.empty() || !renderer) {
          state.ok = kFailed;
        } else if (i < cameras.size()) {
          state = state_of(cameras[i], static_cast<int32_t>(i));
        } else {
          state.ok = kEnd;
        }
      }
      if (auto st = comm_.broadcast(parallel::bytes_of(state), 0); !st) {
        return fatal(st.error().message);
      }
      if (state.ok == kEnd) break;
      if (state.ok == kFailed) {
        if (comm_.rank() != 0) return 1;
        return report_error(!error_.empty() ? error_ : renderer.error().message);
      }
      if (!renderer) return fatal(renderer.error().message);
      auto whole = lod::make_view(camera_of(state));
      if (!whole) return fatal(whole.error().message);
      if (auto st = frame(*setup, **renderer, *whole, path ? state.index : -1); !st) {
        return fatal(st.error().message);
      }
    }
    if (comm_.rank() == 0) write_summary();
    return 0;
  }

 private:
  Result<std::vector<lod::Camera>> still_camera(const RenderSetup& setup) {
    const lod::Camera camera = RELIEF_TRY(parse_camera(args_, setup));
    RELIEF_CHECK(lod::make_view(camera));
    return std::vector<lod::Camera>{camera};
  }

  // The path's frames at --fps (default the path's), as `relief render --path`.
  Result<std::vector<lod::Camera>> path_cameras(const RenderSetup& setup) {
    const view::PathFile file = RELIEF_TRY(view::read_path_file(
        *args_.get("--path"), [&](const std::string& where, const std::vector<double>& values) {
          return camera_from_values(where, values, setup);
        }));
    double fps = file.fps;
    if (auto f = RELIEF_TRY(args_.get_double("--fps"))) {
      if (!(*f > 0 && *f <= 1000)) return fail("--fps: must be in (0, 1000]");
      fps = *f;
    }
    const std::vector<lod::Keyframe>& keys = file.keyframes;
    const double count = std::floor((keys.back().time - keys.front().time) * fps + 1e-9) + 1;
    if (!(count <= kMaxPathFrames)) {
      return fail(fmt::format("{}: {:.6g} frames, more than {} under --parallel",
                              *args_.get("--path"), count, kMaxPathFrames));
    }
    std::vector<lod::Camera> cameras;
    for (size_t i = 0; i < static_cast<size_t>(count); ++i) {
      cameras.push_back(lod::camera_at(keys, keys.front().time + static_cast<double>(i) / fps));
    }
    std::error_code ec;
    std::filesystem::create_directories(*args_.get("--output"), ec);
    if (ec)
      return fail(*args_.get("--output") + ": cannot create the frame directory: " + ec.message());
    return cameras;
  }

  // Every rank's GL context and renderer (a failure here is this rank's).
  Result<std::unique_ptr<parallel::FrameRenderer>> start(RenderSetup& setup) {
    view::SceneOptions so = scene_options(setup);
    so.interactive = false;
    context_ = RELIEF_TRY(render::GlContext::create_headless());
    return parallel::FrameRenderer::create(setup.store, setup.imagery ? &*setup.imagery : nullptr,
                                           so);
  }

  // Where a frame (or a display's part of it) goes: -o for a still, DIR/frame_NNNNN.png
  // for a path; walls add _rR_cC.
  std::string output(int frame_index, int display) const {
    std::string out = *args_.get("--output");
    if (frame_index >= 0) {
      out = (std::filesystem::path(out) / fmt::format("frame_{:05d}.png", frame_index)).string();
    }
    return display >= 0 ? display_file(out, wall_, display) : out;
  }

  // Sort-first gives each rank a screen tile of at least one pixel.
  Status check_screen_tiles(int width, int height) const {
    const auto tiles = parallel::screen_tiles(width, height, mode_.screen, comm_.size());
    if (std::none_of(tiles.begin(), tiles.end(),
                     [](const lod::PixelRect& t) { return t.empty(); })) {
      return {};
    }
    return fail(fmt::format(
        "--parallel {}: a {}x{} view has too few pixels to give each of the {} ranks a screen "
        "tile; give a larger --size or fewer ranks",
        parallel::to_string(mode_), width, height, comm_.size()));
  }
  int same_everywhere(const std::string& message) {
    return comm_.rank() == 0 ? report_error(message) : 1;
  }
  // An error of this rank alone: the others may wait for it, so the run ends.
  [[noreturn]] int fatal(const std::string& message) {
    report_error(comm_.size() > 1 && !message.starts_with("rank ")
                     ? fmt::format("rank {}: {}", comm_.rank(), message)
                     : message);
    std::fflush(stderr);
    comm_.abort(1);
  }

  Status frame(RenderSetup& setup, parallel::FrameRenderer& renderer_ref, const lod::View& whole,
               int frame_index) {
    parallel::FrameRenderer* renderer = &renderer_ref;
    RankStats stats;
    const int n = comm_.size(), me = comm_.rank();
    std::vector<lod::PixelRect> tiles;
    if (mode_.kind == ParallelMode::Kind::sort_first) {
      tiles = parallel::screen_tiles(whole.width, whole.height, mode_.screen, n);
    } else if (mode_.kind == ParallelMode::Kind::wall) {
      for (int i = 0; i < n; ++i) tiles.push_back(wall_.display(i));
    }
    // Screen-space modes select what their window shows, so each rank reads
    // only its part's tiles; sort-last ranks share one selection of the whole.
    lod::View view = whole;
    if (!tiles.empty()) view = RELIEF_TRY(lod::with_window(whole, tiles[static_cast<size_t>(me)]));
    auto began = Clock::now();
    RELIEF_CHECK(renderer->select(view));
    stats.select_ms = ms_since(began);

    std::vector<parallel::TriangleRange> keep;
    if (mode_.kind == ParallelMode::Kind::sort_last) {
      std::vector<geo::TileKey> keys;
      for (const lod::SelectedQuad& q : renderer->selection().quads) keys.push_back(q.key);
      keep =
          parallel::rank_triangles(keys, renderer->quad_triangles(), setup.store.manifest().extent,
                                   mode_.quads, n, me, renderer->splits_quads());
    } else {
      keep = RELIEF_TRY(renderer->quads_in_window(view));
    }
    const int w = view.window.empty() ? whole.width : view.window.width;
    const int h = view.window.empty() ? whole.height : view.window.height;
    auto target = RELIEF_TRY(render::make_offscreen_target(w, h));
    began = Clock::now();
    const render::FrameStats drawn = RELIEF_TRY(renderer->draw(view, keep, *target));
    parallel::Layer layer{w, h, RELIEF_TRY(target->read_rgba()), {}};
    if (mode_.kind == ParallelMode::Kind::sort_last) layer.depth = RELIEF_TRY(target->read_depth());
    stats.render_ms = ms_since(began);
    stats.quads = drawn.quads;
    stats.triangles = drawn.triangles;

    inject_fault(me);
    began = Clock::now();
    const uint64_t bytes_before = comm_.bytes_sent();
    std::vector<uint8_t> image;
    if (mode_.kind == ParallelMode::Kind::sort_last) {
      image = RELIEF_TRY(parallel::depth_composite(comm_, layer, compositing_));
    } else if (mode_.kind == ParallelMode::Kind::sort_first) {
      image =
          RELIEF_TRY(parallel::gather_tiles(comm_, layer.rgba, tiles, whole.width, whole.height));
    } else {
      RELIEF_CHECK(write_png(output(frame_index, me), layer.rgba, w, h));
    }
    stats.composite_ms = ms_since(began);
    stats.bytes_sent = comm_.bytes_sent() - bytes_before;
    if (me == 0 && mode_.kind != ParallelMode::Kind::wall) {
      RELIEF_CHECK(write_png(output(frame_index, -1), image, whole.width, whole.height));
    }
    return report(stats, whole);
  }

  // Gathers every rank's figures on rank 0: --stats and the closing line.
  Status report(const RankStats& mine, const lod::View& whole) {
    const int n = comm_.size();
    std::vector<RankStats> all(static_cast<size_t>(n));
    all[0] = mine;
    if (comm_.rank() != 0) {
      const Comm::Send send{0, std::as_bytes(std::span(&mine, 1))};
      return comm_.exchange(std::span(&send, 1), {});
    }
    std::vector<Comm::Receive> receives;
    for (int k = 1; k < n; ++k) {
      receives.push_back({k, std::as_writable_bytes(std::span(&all[static_cast<size_t>(k)], 1))});
    }
    RELIEF_CHECK(comm_.exchange({}, receives));
    std::vector<uint64_t> triangles;
    nlohmann::json ranks = nlohmann::json::array();
    for (const RankStats& s : all) {
      triangles.push_back(s.triangles);
      ranks.push_back({{"quads", s.quads},
                       {"triangles", s.triangles},
                       {"select_ms", s.select_ms},
                       {"render_ms", s.render_ms},
                       {"composite_ms", s.composite_ms},
                       {"bytes_sent", s.bytes_sent}});
    }
    const double imbalance = parallel::imbalance(triangles);
    frames_.push_back({{"ranks", ranks}, {"triangle_imbalance", imbalance}});
    width_ = whole.width, height_ = whole.height;
    return {};
  }

  // Rank 0: --stats (a still's ranks, or every frame's) and the closing line.
  void write_summary() {
    double worst = 0;
    for (const nlohmann::json& f : frames_) {
      worst = std::max(worst, f["triangle_imbalance"].get<double>());
    }
    if (auto path = args_.get("--stats")) {
      nlohmann::json stats = {{"mode", parallel::to_string(mode_)},
                              {"ranks_count", comm_.size()},
                              {"width", width_},
                              {"height", height_}};
      if (mode_.kind == ParallelMode::Kind::sort_last) {
        stats["compositing"] = parallel::to_string(compositing_);
        stats["composite_rounds"] = parallel::composite_rounds(compositing_, comm_.size());
      }
      if (args_.get("--path")) {
        stats["frames"] = frames_;
      } else {
        stats["ranks"] = frames_.at(0)["ranks"];
        stats["triangle_imbalance"] = frames_.at(0)["triangle_imbalance"];
      }
      if (auto st = write_json(*path, stats.dump(1)); !st) {
        fatal(st.error().message);
      }
    }
    std::printf(
        "wrote %s: %zu frame(s) of %dx%d, %s on %d ranks, triangles per rank max/mean - 1 <= "
        "%.3f\n",
        args_.get("--output")->c_str(), frames_.size(), width_, height_,
        parallel::to_string(mode_).c_str(), comm_.size(), worst);
  }

  static constexpr double kMaxPathFrames = 100000;
  const Args& args_;
  const ParallelMode& mode_;
  const parallel::Compositing& compositing_;
  Comm& comm_;
  parallel::Wall wall_;
  std::string error_;
  std::unique_ptr<render::GlContext> context_;
  std::vector<nlohmann::json> frames_;
  int width_ = 0, height_ = 0;
};

}  // namespace

int render_parallel(const Args& args) {
  // A bad mode is said before MPI starts (by every rank alike).
  auto mode = parallel::parse_parallel_mode(*args.get("--parallel"));
  if (!mode) return report_error(mode.error().message);
  parallel::Compositing compositing;
  if (auto c = args.get("--composite")) {
    if (mode->kind != ParallelMode::Kind::sort_last) {
      return report_error("--composite: only with --parallel sort-last:...");
    }
    auto parsed = parallel::parse_compositing(*c);
    if (!parsed) return report_error(parsed.error().message);
    compositing = *parsed;
  }
  double timeout = 60;
  if (auto t = args.get("--parallel-timeout")) {
    char* end = nullptr;
    timeout = std::strtod(t->c_str(), &end);
    if (end == t->c_str() || *end || !(timeout > 0 && timeout <= 86400)) {
      return report_error(fmt::format("--parallel-timeout: '{}' is not seconds in (0, 86400]", *t));
    }
  }
  auto comm = Comm::init(timeout);
  if (!comm) return report_error(comm.error().message);
  return Run(args, *mode, compositing, **comm).run();
}

}  // namespace relief::cli
