#pragma once
// Plays a camera path (keyframes, lod/camera_path.h) through a Scene: one
// frame every 1/fps seconds of path time, paced on the clock in interactive
// mode (a frame that takes longer is not made up for: the next one is drawn
// at once); after the path's end, interactive playback keeps drawing the last
// camera until a frame is complete or a time limit passes, each frame once
// something arrived (Scene::wait_for_change; no sooner than 1/fps after the
// previous one) rather than the same frame again. Reports what a
// streaming benchmark needs: frame times, completion after each cut, and the
// bytes the frames drew against the bytes fetched.
#include <functional>
#include <optional>
#include <vector>

#include "relief/lod/camera_path.h"
#include "relief/view/scene.h"

namespace relief::view {

struct PathOptions {
  double fps = 30;
  double until_complete = 0;  // seconds, interactive only
  // An interactive scene made to draw complete frames (movie export), not
  // paced: before each frame, its tiles are requested and waited for on the
  // loaders' threads while the camera `lookahead_s` further along the path
  // is prefetched, so reading, decoding and diamond errors overlap the
  // frames before. A frame not complete after that (imagery) is drawn again
  // once the loaders are idle. Fails if tiles cannot be loaded.
  bool wait_complete = false;
  double lookahead_s = 0.5;
};

struct FrameRecord {
  size_t index = 0;
  double time = 0;  // seconds since playback started, on the clock, at the frame's start
  FrameReport report;
};

struct CutReport {
  size_t frame = 0;                        // the first frame after the cut
  std::optional<double> complete_after_s;  // until the first complete frame; none: never
};

struct PathSummary {
  size_t frames = 0;
  double p50_frame_ms = 0, p99_frame_ms = 0, max_frame_ms = 0, p50_cpu_ms = 0, p99_cpu_ms = 0;
  bool complete = false;  // the last frame
  std::vector<CutReport> cuts;
  // File bytes of the elevation tiles the last frame drew (with level 0: the
  // least a cold cache must fetch for it), and of every tile any frame drew
  // with the ancestors a coarse-first loader fetches before them.
  uint64_t final_view_bytes = 0, drawn_bytes = 0;
};

struct PathCallbacks {
  std::function<void(size_t index)> frame_start;         // before a frame's selection
  std::function<Status(const FrameRecord&)> frame_done;  // after it is drawn (write it out)
};

// Frames of a path of `frame_count` frames (the caller bounds it).
Result<PathSummary> play_path(Scene& scene, const std::vector<lod::Keyframe>& keys,
                              size_t frame_count, const PathOptions& options,
                              render::RenderTarget& target, const Clock& clock,
                              const PathCallbacks& callbacks = {});

// The p-th quantile (0..1) of `values`, the nearest-rank way; 0 when empty.
double percentile(std::vector<double> values, double p);

}  // namespace relief::view
