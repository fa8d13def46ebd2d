#include "relief/view/target_hints.h"

#include <algorithm>
#include <cassert>
#include <cmath>
#include <condition_variable>
#include <deque>
#include <limits>
#include <map>
#include <mutex>
#include <numbers>
#include <set>
#include <thread>

#include <fmt/format.h>

#include "relief/lod/selection.h"
#include "relief/lod/vec.h"

namespace relief::view {
namespace {

process::ConstView view_of(const tiles::Raster& r, int64_t origin_x, int64_t origin_y) {
  return {r.f32().data(), r.width(), r.height(), r.width(), origin_x, origin_y};
}

}  // namespace

std::vector<TargetHint> detect_in_tile(const geo::TileGrid& grid, const geo::TileKey& key,
                                       const tiles::Raster& bordered, int border,
                                       double max_amplitude,
                                       const process::DetectorParams& params) {
  assert(border >= process::kDetectorMargin);
  const int w = grid.width(), h = grid.height(), m = process::kDetectorMargin;
  const int64_t x0 = static_cast<int64_t>(key.x) * w, y0 = static_cast<int64_t>(key.y) * h;
  // The interior and the detector's margin around it, in global coordinates.
  const process::ConstView in = view_of(bordered, x0 - border, y0 - border)
                                    .window(border - m, border - m, w + 2 * m, h + 2 * m);
  std::vector<TargetHint> out;
  for (const process::Detection& d : process::detect_point_targets(in, max_amplitude, params)) {
    TargetHint hint;
    hint.tile = key;
    hint.detection = d;
    hint.lon = grid.sample_lon(key, static_cast<double>(d.x - x0));
    hint.lat = grid.sample_lat(key, static_cast<double>(d.y - y0));
    out.push_back(hint);
  }
  return out;
}

std::vector<render::OverlayLine> hint_glyphs(
    const lod::View& view, std::span<const TargetHint> hints, const HintStyle& style,
    const std::function<double(double lon, double lat)>& height) {
  std::vector<render::OverlayLine> lines;
  const double r = style.radius_px;
  for (const TargetHint& hint : hints) {
    const double h = height ? height(hint.lon, hint.lat) : 0.0;
    const lod::Vec3 p = lod::ecef(hint.lon, hint.lat, h);
    double sx = 0, sy = 0;
    if (lod::below_horizon(view.eye, p, 0) || !view.project(p, sx, sy)) continue;
    if (sx < -r || sy < -r || sx > view.width + r || sy > view.height + r) continue;
    const std::array<uint8_t, 4> colour =
        hint.detection.pslr_db <= style.good_pslr_db ? style.good : style.bad;
    auto line = [&](double ax, double ay, double bx, double by, std::array<uint8_t, 4> c) {
      lines.push_back({static_cast<float>(ax), static_cast<float>(ay), static_cast<float>(bx),
                       static_cast<float>(by), c});
    };
    constexpr int kSegments = 24;
    for (int k = 0; k < kSegments; ++k) {
      const double a0 = 2 * std::numbers::pi * k / kSegments,
                   a1 = 2 * std::numbers::pi * (k + 1) / kSegments;
      line(sx + r * std::cos(a0), sy + r * std::sin(a0), sx + r * std::cos(a1),
           sy + r * std::sin(a1), colour);
    }
    // The side-lobe axes: counter-clockwise from east on the image, north up.
    // Their screen directions come from projecting a point a little along each.
    const double step = 1e-4;  // degrees: small next to any tile, large next to float noise
    for (const double deg : hint.detection.direction) {
      const double a = deg * std::numbers::pi / 180;
      const double lon =
          hint.lon + step * std::cos(a) / std::cos(hint.lat * std::numbers::pi / 180);
      const double lat = hint.lat + step * std::sin(a);
      double qx = 0, qy = 0;
      if (!view.project(lod::ecef(lon, lat, h), qx, qy)) continue;
      const double dx = qx - sx, dy = qy - sy, len = std::hypot(dx, dy);
      if (!(len > 0)) continue;
      const double ux = dx / len * 1.8 * r, uy = dy / len * 1.8 * r;
      line(sx - ux, sy - uy, sx + ux, sy + uy, style.axes);
    }
    // The PSLR bar under the circle: its length grows with the side lobes'
    // strength, full width at 0 dB, none at -30 dB.
    const double strength = std::clamp((hint.detection.pslr_db + 30) / 30, 0.0, 1.0);
    const double by = sy + 1.5 * r;
    line(sx - r, by, sx - r + 2 * r * strength, by, colour);
    line(sx - r, by + 1, sx - r + 2 * r * strength, by + 1, colour);
  }
  return lines;
}

struct TargetHints::Impl {
  const tiles::Store& store;
  process::DetectorParams params;
  double max_amplitude = 0;
  mutable std::mutex mutex;
  std::condition_variable wake;
  std::map<geo::TileKey, std::vector<TargetHint>> done;
  std::map<geo::TileKey, std::string> failed;
  std::deque<geo::TileKey> queue;
  std::set<geo::TileKey> queued;
  bool stopping = false;
  std::function<void()> on_detected;
  std::thread worker;

  Impl(const tiles::Store& s, const process::DetectorParams& p) : store(s), params(p) {
    max_amplitude = store.manifest().stats.max;
  }

  Result<std::vector<TargetHint>> detect(const geo::TileKey& key) const {
    const tiles::Tile tile = RELIEF_TRY(store.read_tile(key));
    return detect_in_tile(store.grid(), key, tile.raster, store.manifest().border, max_amplitude,
                          params);
  }

  void store_result(const geo::TileKey& key, Result<std::vector<TargetHint>> r) {
    std::lock_guard lock(mutex);
    if (r) {
      done[key] = std::move(*r);
    } else {
      failed[key] = r.error().message;
    }
  }

  void run() {
    for (;;) {
      geo::TileKey key;
      {
        std::unique_lock lock(mutex);
        wake.wait(lock, [&] { return stopping || !queue.empty(); });
        if (stopping) return;
        key = queue.front();
        queue.pop_front();
        queued.erase(key);
      }
      store_result(key, detect(key));
      if (on_detected) on_detected();
    }
  }
};

TargetHints::TargetHints(std::unique_ptr<Impl> impl) : impl_(std::move(impl)) {}

TargetHints::~TargetHints() {
  {
    std::lock_guard lock(impl_->mutex);
    impl_->stopping = true;
  }
  impl_->wake.notify_all();
  if (impl_->worker.joinable()) impl_->worker.join();
}

Result<std::unique_ptr<TargetHints>> TargetHints::create(const tiles::Store& store,
                                                         const process::DetectorParams& params,
                                                         std::function<void()> on_detected) {
  const tiles::Manifest& m = store.manifest();
  if (m.kind != tiles::DatasetKind::Sar || m.sample_type != tiles::SampleType::Float32 ||
      m.bands != 1) {
    return fail(fmt::format("{}: the detector needs a SAR amplitude store, not {}",
                            store.root().string(), tiles::to_string(m.kind)));
  }
  if (m.border < process::kDetectorMargin) {
    return fail(fmt::format("{}: a border of {} samples, the detector needs {}",
                            store.root().string(), m.border, process::kDetectorMargin));
  }
  if (!(m.stats.max > 0)) {
    return fail(store.root().string() + ": no positive amplitude in the store's statistics");
  }
  auto impl = std::make_unique<Impl>(store, params);
  impl->on_detected = std::move(on_detected);
  Impl* raw = impl.get();
  impl->worker = std::thread([raw] { raw->run(); });
  return std::unique_ptr<TargetHints>(new TargetHints(std::move(impl)));
}

Result<HintSet> TargetHints::hints(std::span<const geo::TileKey> tiles, bool wait) {
  Impl& s = *impl_;
  HintSet set;
  std::vector<TargetHint>& out = set.hints;
  std::vector<geo::TileKey> missing;
  {
    std::lock_guard lock(s.mutex);
    for (const geo::TileKey& key : tiles) {
      if (!s.store.has_tile(key)) continue;
      if (auto f = s.failed.find(key); f != s.failed.end()) return fail(f->second);
      if (auto d = s.done.find(key); d != s.done.end()) {
        out.insert(out.end(), d->second.begin(), d->second.end());
      } else {
        missing.push_back(key);
      }
    }
  }
  if (wait) {
    for (const geo::TileKey& key : missing) {
      auto r = s.detect(key);
      if (!r) return fail(r.error().message);
      out.insert(out.end(), r->begin(), r->end());
      s.store_result(key, std::move(*r));
    }
  } else if (!missing.empty()) {
    {
      std::lock_guard lock(s.mutex);
      for (const geo::TileKey& key : missing) {
        if (s.queued.insert(key).second) s.queue.push_back(key);
      }
    }
    s.wake.notify_one();
    set.missing = missing.size();
  }
  return set;
}

Result<process::TargetAnalysis> TargetHints::analyse(const TargetHint& hint,
                                                     int half_length) const {
  const tiles::Store& store = impl_->store;
  const tiles::Tile tile = RELIEF_TRY(store.read_tile(hint.tile));
  const int border = store.manifest().border;
  const int64_t x0 = static_cast<int64_t>(hint.tile.x) * store.grid().width() - border,
                y0 = static_cast<int64_t>(hint.tile.y) * store.grid().height() - border;
  // A window of 2 (half_length + 1) + 1 samples around the target; what the
  // tile does not hold stays NaN (no data in the sections).
  const int n = 2 * (half_length + 1) + 1;
  tiles::Raster window(tiles::SampleType::Float32, 1, n, n);
  auto out = window.f32();
  std::fill(out.begin(), out.end(), std::numeric_limits<float>::quiet_NaN());
  const auto in = tile.raster.f32();
  const int64_t wx = hint.detection.x - (half_length + 1),
                wy = hint.detection.y - (half_length + 1);
  for (int j = 0; j < n; ++j) {
    const int64_t ty = wy + j - y0;
    if (ty < 0 || ty >= tile.raster.height()) continue;
    for (int i = 0; i < n; ++i) {
      const int64_t tx = wx + i - x0;
      if (tx < 0 || tx >= tile.raster.width()) continue;
      out[static_cast<size_t>(j) * n + i] =
          in[static_cast<size_t>(ty) * tile.raster.width() + static_cast<size_t>(tx)];
    }
  }
  return process::analyse_point_target(view_of(window, wx, wy), hint.detection, half_length);
}

size_t TargetHints::tiles_detected() const {
  std::lock_guard lock(impl_->mutex);
  return impl_->done.size();
}

}  // namespace relief::view
