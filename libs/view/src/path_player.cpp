#include "relief/view/path_player.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <optional>
#include <thread>
#include <unordered_set>

#include <fmt/format.h>

namespace relief::view {

namespace {

using TileSet = std::unordered_set<geo::TileKey, geo::TileKeyHash>;

// After the path, an incomplete view is drawn again when something arrived,
// or after this long (real time: a safety timeout, as the viewer's).
constexpr double kSettleWait = 0.25;

// Adds the data tiles a selection draws (own and parent data) to `tiles`;
// with `ancestors`, also the tiles above them, which a coarse-first loader
// must have fetched before.
void add_drawn(TileSet& tiles, lod::TerrainModel& terrain, const lod::Selection& selection,
               bool ancestors) {
  for (const auto& q : selection.quads) {
    for (const auto& w : {terrain.window(q.key), terrain.parent_window(q.key)}) {
      if (!w.tile) continue;
      for (std::optional<geo::TileKey> k = *w.tile; k; k = ancestors ? k->parent() : std::nullopt) {
        if (!tiles.insert(*k).second && ancestors) break;  // its ancestors are in already
      }
    }
  }
}

uint64_t file_bytes(const tiles::Store& store, const TileSet& tiles) {
  uint64_t bytes = 0;
  for (const auto& k : tiles) {
    if (const auto* e = store.index(k.level).find(k)) bytes += e->file_bytes;
  }
  return bytes;
}

// Waits (polling: the loaders' threads have no completion signal) until
// the scene's loaders have nothing queued or loading.
void wait_idle(Scene& scene) {
  for (stream::TileLoader* loader : {scene.elevation_loader(), scene.imagery_loader()}) {
    while (loader && !loader->idle()) std::this_thread::sleep_for(std::chrono::milliseconds(1));
  }
}

// Requests `camera`'s tiles until none is missing, without drawing (level
// by level: a coarse-first loader asks for a tile once its parent is in).
Status wait_resident(Scene& scene, const lod::Camera& camera, size_t index) {
  constexpr int kMaxRounds = 1000;
  std::optional<uint64_t> settled;  // tiles loaded or failed at the last round
  for (int round = 0;; ++round) {
    const uint32_t waiting = RELIEF_TRY(scene.request(camera));
    if (waiting == 0) return {};
    // request() asked for everything missing: if the loader has nothing to
    // do and loaded nothing since the last round, the quads wait for tiles
    // that failed (and wait out their retry pause).
    const stream::LoaderStats s = scene.elevation_loader()->stats();
    const uint64_t done = s.loaded + s.failed;
    if ((s.queued == 0 && s.in_flight == 0 && settled == done) || round == kMaxRounds) {
      return fail(fmt::format("frame {}: {} quads wait for elevation tiles that failed to load",
                              index, waiting));
    }
    settled = done;
    wait_idle(scene);
  }
}

// PathOptions::wait_complete. A frame whose tiles the path's prefetch
// brought in is drawn once (its selection also prefetches further on); a
// fresh view (the first frame, after a cut) or a frame that found tiles
// missing waits for them without drawing, then draws again.
Result<FrameReport> draw_complete(Scene& scene, const lod::Camera& camera, size_t index, bool fresh,
                                  render::RenderTarget& target) {
  constexpr int kMaxDraws = 100;
  if (fresh) RELIEF_CHECK(wait_resident(scene, camera, index));
  for (int draws = 1;; ++draws) {
    FrameReport report = RELIEF_TRY(scene.draw(camera, target));
    if (report.complete) return report;
    if (draws == kMaxDraws) {
      return fail(fmt::format("frame {}: not complete after {} draws (tiles failing to load)",
                              index, draws));
    }
    RELIEF_CHECK(wait_resident(scene, camera, index));
    wait_idle(scene);  // imagery, requested by the draw
  }
}

}  // namespace

double percentile(std::vector<double> v, double p) {
  if (v.empty()) return 0;
  std::sort(v.begin(), v.end());
  const size_t i = std::min(
      v.size() - 1,
      static_cast<size_t>(std::max(1.0, std::ceil(p * static_cast<double>(v.size())))) - 1);
  return v[i];
}

Result<PathSummary> play_path(Scene& scene, const std::vector<lod::Keyframe>& keys,
                              size_t frame_count, const PathOptions& options,
                              render::RenderTarget& target, const Clock& clock,
                              const PathCallbacks& callbacks) {
  const bool interactive = scene.options().interactive;
  const tiles::Store* store = scene.terrain().store();
  std::vector<double> frame_ms, cpu_ms, frame_times;
  std::vector<bool> complete_frames;
  std::vector<std::pair<size_t, double>> cuts;  // first frame after (1-based, 0: not yet), time
  for (size_t k = 1; k < keys.size(); ++k) {
    if (keys[k].cut) cuts.emplace_back(0, keys[k].time);
  }
  TileSet drawn;
  PathSummary summary;
  const auto start = clock.now();
  double settle_start = -1;
  for (size_t index = 0;; ++index) {
    const bool on_path = index < frame_count;
    if (!on_path) {
      if (!interactive || options.wait_complete || summary.complete) break;
      const double now = seconds_between(start, clock.now());
      if (settle_start < 0) settle_start = now;
      if (now - settle_start >= options.until_complete) break;
    }
    const double t =
        keys.front().time + static_cast<double>(std::min(index, frame_count - 1)) / options.fps;
    const lod::Camera camera = lod::camera_at(keys, t);
    bool fresh = index == 0;  // a view with nothing prefetched for it
    for (auto& [frame_of_cut, time] : cuts) {
      if (!frame_of_cut && t >= time) {
        frame_of_cut = index + 1;
        scene.cut();
        fresh = true;
      }
    }
    if (callbacks.frame_start) callbacks.frame_start(index);
    const uint64_t changes = interactive ? scene.changes() : 0;
    const auto frame_start = clock.now();
    FrameRecord record;
    record.index = index;
    record.time = seconds_between(start, frame_start);
    if (options.wait_complete) {
      scene.set_prefetch_camera(lod::camera_at(keys, t + options.lookahead_s));
      record.report = RELIEF_TRY(draw_complete(scene, camera, index, fresh, target));
    } else {
      record.report = RELIEF_TRY(scene.draw(camera, target));
    }
    summary.complete = record.report.complete;
    frame_ms.push_back(record.report.frame_seconds * 1e3);
    cpu_ms.push_back(record.report.cpu_seconds * 1e3);
    frame_times.push_back(record.time);
    complete_frames.push_back(record.report.complete);
    if (store) add_drawn(drawn, scene.terrain(), scene.last_selection(), true);
    if (callbacks.frame_done) RELIEF_CHECK(callbacks.frame_done(record));
    if (interactive && !options.wait_complete) {
      // Settling after the path: the same camera again would draw the same
      // frame until the loaders (or detections) bring something, so wait for
      // that (they have the cores meanwhile; at most kSettleWait, which also
      // lets a failed tile be asked for again).
      if (!on_path && !record.report.complete && !record.report.draws_more) {
        scene.wait_for_change(changes, kSettleWait);
      }
      // Real time: the next frame is due 1/fps after this one.
      clock.sleep_until(frame_start + std::chrono::duration_cast<Clock::Duration>(
                                          std::chrono::duration<double>(1 / options.fps)));
    }
  }
  if (options.wait_complete) scene.set_prefetch_camera(std::nullopt);
  summary.frames = frame_ms.size();
  summary.p50_frame_ms = percentile(frame_ms, 0.5);
  summary.p99_frame_ms = percentile(frame_ms, 0.99);
  summary.max_frame_ms = percentile(frame_ms, 1.0);
  summary.p50_cpu_ms = percentile(cpu_ms, 0.5);
  summary.p99_cpu_ms = percentile(cpu_ms, 0.99);
  for (const auto& [frame_of_cut, time] : cuts) {
    if (!frame_of_cut) continue;
    CutReport c{frame_of_cut - 1, std::nullopt};
    for (size_t i = c.frame; i < complete_frames.size(); ++i) {
      if (complete_frames[i]) {
        c.complete_after_s = frame_times[i] - frame_times[c.frame];
        break;
      }
    }
    summary.cuts.push_back(c);
  }
  if (store) {
    TileSet last;
    for (const tiles::IndexEntry& e : store->index(0).entries()) last.insert(e.key);
    add_drawn(last, scene.terrain(), scene.last_selection(), false);
    summary.final_view_bytes = file_bytes(*store, last);
    summary.drawn_bytes = file_bytes(*store, drawn);
  }
  return summary;
}

}  // namespace relief::view
