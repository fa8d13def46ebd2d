#pragma once
// Detector hints at draw time (seed 003 §1.5.3, §2.4): the point-target
// detector of the process library runs on the tiles of a SAR amplitude store
// that a frame shows, off the render thread, and each detection becomes a
// hint drawn at its place on the globe: a circle, a cross along its two
// side-lobe axes and a bar for its rough PSLR. Interactive frames draw the
// hints of the tiles detected so far (a frame never waits); complete frames
// detect every tile they show first.
//
// A tile is detected on its own interior with its overlap border as the
// detector's margin, so the hints of a level's tiles are the detections of
// the whole level, tile seams included (tested).
#include <array>
#include <cstddef>
#include <cstdint>
#include <functional>
#include <memory>
#include <span>
#include <vector>

#include "relief/base/result.h"
#include "relief/geo/tile_grid.h"
#include "relief/lod/camera.h"
#include "relief/process/point_targets.h"
#include "relief/render/overlay.h"
#include "relief/tiles/raster.h"
#include "relief/tiles/store.h"

namespace relief::view {

struct TargetHint {
  geo::TileKey tile;             // where it was detected
  double lon = 0, lat = 0;       // the peak sample's centre, degrees
  process::Detection detection;  // x, y: global sample coordinates at tile.level
};

// The detections in the interior of tile `key`, whose raster `bordered`
// carries `border` >= process::kDetectorMargin overlap samples (nodata NaN).
std::vector<TargetHint> detect_in_tile(const geo::TileGrid& grid, const geo::TileKey& key,
                                       const tiles::Raster& bordered, int border,
                                       double max_amplitude, const process::DetectorParams& params);

struct HintStyle {
  double radius_px = 9;
  // PSLR at or below this (the ideal sinc's -13.26 dB, rounded) is drawn
  // green, above it red: a target whose side lobes are too strong.
  double good_pslr_db = -13;
  std::array<uint8_t, 4> good = {60, 230, 90, 255}, bad = {240, 60, 50, 255};
  std::array<uint8_t, 4> axes = {255, 255, 255, 255};
};

// The hints as overlay lines seen through `view`: hints behind the horizon
// or off screen are left out. `height` gives the terrain height (metres) at
// a lon/lat (nullptr: the ellipsoid).
std::vector<render::OverlayLine> hint_glyphs(
    const lod::View& view, std::span<const TargetHint> hints, const HintStyle& style = {},
    const std::function<double(double lon, double lat)>& height = nullptr);

// The hints of some tiles, and how many of those tiles are still being
// detected (their hints are not in `hints` yet).
struct HintSet {
  std::vector<TargetHint> hints;
  size_t missing = 0;
};

// The hints of a store's tiles, detected on a worker thread and cached per
// tile. Thread-safe.
class TargetHints {
 public:
  // `store` must outlive this; single-band (SAR amplitude) stores only.
  // `on_detected` (may be null) is called on the worker after each tile it
  // detected (or failed to).
  static Result<std::unique_ptr<TargetHints>> create(const tiles::Store& store,
                                                     const process::DetectorParams& params,
                                                     std::function<void()> on_detected = nullptr);
  ~TargetHints();
  TargetHints(const TargetHints&) = delete;
  TargetHints& operator=(const TargetHints&) = delete;

  // The hints of `tiles` detected so far; the others are queued for the
  // worker. With `wait`, detects the missing ones on the calling thread
  // first. Tiles the store does not have give none.
  Result<HintSet> hints(std::span<const geo::TileKey> tiles, bool wait);
  // The analysis of a hint (cross-sections along both axes, PSLR, -3 dB
  // widths) from its tile, `half_length` samples either side at most (the
  // tile and its border bound it; beyond, the sections are NaN).
  Result<process::TargetAnalysis> analyse(const TargetHint& hint, int half_length) const;
  size_t tiles_detected() const;

 private:
  struct Impl;
  explicit TargetHints(std::unique_ptr<Impl> impl);
  std::unique_ptr<Impl> impl_;
};

}  // namespace relief::view
