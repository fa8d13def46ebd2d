// Detector hints at draw time: tiles detected with their borders as margin
// give exactly the detections of the whole level; the worker thread's hints
// equal those detected inline; glyphs are placed at the projected peak and
// left out behind the horizon; the overlay draws them over a frame.
#include <gtest/gtest.h>

#include <atomic>
#include <chrono>
#include <cmath>
#include <functional>
#include <limits>
#include <set>
#include <thread>

#include "../ingest/built_stores.h"
#include "../support/images.h"
#include "../support/test_support.h"
#include "gl_scene_test.h"
#include "relief/render/overlay.h"
#include "relief/view/scene.h"
#include "relief/view/target_hints.h"

namespace relief::view {
namespace {

using namespace std::chrono_literals;

std::vector<geo::TileKey> level_tiles(const tiles::Store& s, int level) {
  std::vector<geo::TileKey> keys;
  for (const auto& e : s.index(level).entries()) keys.push_back(e.key);
  return keys;
}

using Peak = std::tuple<int64_t, int64_t, double>;  // x, y, amplitude

TEST(TargetHints, TilesWithTheirBordersGiveTheWholeLevelsDetections) {
  const tiles::Store& s = sar();
  const int level = s.manifest().max_level, w = s.grid().width(), h = s.grid().height();
  const std::vector<geo::TileKey> keys = level_tiles(s, level);
  ASSERT_FALSE(keys.empty());
  // The level as one image, nodata around and between tiles.
  int64_t x0 = INT64_MAX, y0 = INT64_MAX, x1 = 0, y1 = 0;
  for (const auto& k : keys) {
    x0 = std::min<int64_t>(x0, k.x), y0 = std::min<int64_t>(y0, k.y);
    x1 = std::max<int64_t>(x1, k.x), y1 = std::max<int64_t>(y1, k.y);
  }
  const int m = process::kDetectorMargin, border = s.manifest().border;
  const int W = static_cast<int>(x1 - x0 + 1) * w + 2 * m,
            H = static_cast<int>(y1 - y0 + 1) * h + 2 * m;
  std::vector<float> whole(static_cast<size_t>(W) * H, std::numeric_limits<float>::quiet_NaN());
  const double max_amplitude = s.manifest().stats.max;
  const process::DetectorParams params;
  std::set<Peak> from_tiles;
  for (const auto& k : keys) {
    auto tile = s.read_tile(k);
    ASSERT_TRUE(tile) << tile.error().message;
    const auto in = tile->raster.f32();
    for (int j = 0; j < h; ++j) {
      for (int i = 0; i < w; ++i) {
        whole[static_cast<size_t>((k.y - y0) * h + j + m) * W + (k.x - x0) * w + i + m] =
            in[static_cast<size_t>(j + border) * tile->raster.width() + i + border];
      }
    }
    for (const TargetHint& hint :
         detect_in_tile(s.grid(), k, tile->raster, border, max_amplitude, params)) {
      EXPECT_EQ(hint.tile, k);
      EXPECT_NEAR(hint.lon, s.grid().sample_lon(k, static_cast<double>(hint.detection.x - k.x * w)),
                  1e-12);
      from_tiles.insert({hint.detection.x, hint.detection.y, hint.detection.amplitude});
    }
  }
  const process::ConstView all{whole.data(), W, H, W, x0 * w - m, y0 * h - m};
  std::set<Peak> from_level;
  for (const auto& d : process::detect_point_targets(all, max_amplitude, params)) {
    from_level.insert({d.x, d.y, d.amplitude});
  }
  EXPECT_GT(from_level.size(), 0u);
  EXPECT_EQ(from_tiles, from_level);
}

TEST(TargetHints, TheWorkersHintsEqualInlineDetectionAndFramesNeverWait) {
  const tiles::Store& s = sar();
  const std::vector<geo::TileKey> keys = level_tiles(s, s.manifest().max_level);
  auto background = TargetHints::create(s, {});
  ASSERT_TRUE(background) << background.error().message;
  auto first = (*background)->hints(keys, false);
  ASSERT_TRUE(first);
  for (int i = 0; i < 60000 && (*background)->tiles_detected() < keys.size(); ++i) {
    std::this_thread::sleep_for(1ms);
  }
  ASSERT_EQ((*background)->tiles_detected(), keys.size());
  auto later = (*background)->hints(keys, false);
  auto inline_hints = TargetHints::create(s, {});
  ASSERT_TRUE(inline_hints);
  auto waited = (*inline_hints)->hints(keys, true);
  ASSERT_TRUE(later && waited);
  // Nothing was detected before the first call: every tile was queued.
  EXPECT_EQ(first->missing, keys.size());
  EXPECT_TRUE(first->hints.empty());
  EXPECT_EQ(later->missing, 0u);
  EXPECT_EQ(waited->missing, 0u);
  ASSERT_EQ(later->hints.size(), waited->hints.size());
  EXPECT_GT(waited->hints.size(), 0u);
  for (size_t i = 0; i < waited->hints.size(); ++i) {
    EXPECT_EQ(later->hints[i].detection.x, waited->hints[i].detection.x);
    EXPECT_EQ(later->hints[i].detection.y, waited->hints[i].detection.y);
  }
  // The analysis of the strongest hint: both axes measured.
  const TargetHint& strongest = *std::max_element(
      waited->hints.begin(), waited->hints.end(),
      [](const auto& a, const auto& b) { return a.detection.amplitude < b.detection.amplitude; });
  auto analysis = (*inline_hints)->analyse(strongest, 16);
  ASSERT_TRUE(analysis) << analysis.error().message;
  EXPECT_EQ(analysis->x, strongest.detection.x);
  EXPECT_GT(analysis->axes[0].width_3db, 0);
}

TEST(TargetHints, GlyphsSitAtTheProjectedPeakAndNotBehindTheHorizon) {
  TargetHint hint;
  hint.lon = 169.44, hint.lat = -19.53;
  hint.detection.direction[0] = 0, hint.detection.direction[1] = 90;
  hint.detection.pslr_db = -20;
  auto above = lod::make_view(lod::look_at(hint.lon, hint.lat, 0, 5000, 0, -90, 60, 200, 200));
  ASSERT_TRUE(above);
  const auto lines = hint_glyphs(*above, std::span(&hint, 1));
  ASSERT_EQ(lines.size(), 24u + 2u + 2u);  // circle, axes, bar
  // The circle's points are 9 px from the centre of the view (the peak).
  for (int k = 0; k < 24; ++k) {
    EXPECT_NEAR(std::hypot(lines[k].x0 - 100.0, lines[k].y0 - 100.0), 9.0, 0.05);
  }
  // Looking straight down with north up: axis 0 (east) is horizontal on screen.
  EXPECT_NEAR(lines[24].y0, lines[24].y1, 0.05);
  EXPECT_NEAR(lines[25].x0, lines[25].x1, 0.05);
  // From the other side of the Earth: nothing.
  auto antipode =
      lod::make_view(lod::look_at(hint.lon - 180, -hint.lat, 0, 5000, 0, -90, 60, 200, 200));
  ASSERT_TRUE(antipode);
  EXPECT_TRUE(hint_glyphs(*antipode, std::span(&hint, 1)).empty());
}

TEST(TargetHints, TheOverlayDrawsLinesOverAFrameAndBadStoresAreRefused) {
  auto context = render::GlContext::create_headless();
  ASSERT_TRUE(context) << context.error().message;
  auto target = render::make_offscreen_target(64, 32);
  ASSERT_TRUE(target);
  (*target)->bind();
  auto overlay = render::Overlay::create();
  ASSERT_TRUE(overlay) << overlay.error().message;
  const render::OverlayLine line{4, 10, 60, 10, {255, 0, 0, 255}};
  ASSERT_TRUE((*overlay)->draw(std::span(&line, 1), **target));
  auto rgba = (*target)->read_rgba();
  ASSERT_TRUE(rgba);
  auto px = [&](int x, int y) { return &(*rgba)[(static_cast<size_t>(y) * 64 + x) * 4]; };
  EXPECT_EQ(px(30, 10)[0], 255);
  EXPECT_EQ(px(30, 10)[1], 0);
  EXPECT_NE(px(30, 20)[0], 255);  // off the line: untouched
  auto elevation = TargetHints::create(testing::pyrenees_store(), {});
  ASSERT_FALSE(elevation);
  EXPECT_NE(elevation.error().message.find("needs a SAR amplitude store"), std::string::npos);
}

// Frames of the SAR image on the bare ellipsoid, with and without hints.
class SceneHints : public GlSceneTest {
 protected:
  void SetUp() override { set_up_gl(kCamera.width, kCamera.height_px); }

  Result<std::unique_ptr<Scene>> scene(bool detect, bool interactive,
                                       const tiles::Store& store = sar(),
                                       std::function<void()> on_change = nullptr) {
    SceneOptions o;
    o.interactive = interactive;
    o.detect = detect;
    o.on_change = std::move(on_change);
    render::TextureLayer l;
    l.store = &store;
    l.range_max = static_cast<float>(store.manifest().stats.mean * 3);
    o.texture_layers.push_back(l);
    o.selection.texture = &store;  // quads down to the texture's finest level
    return Scene::create(nullptr, nullptr, o, clock_);
  }

  // Straight down from 400 m on the image's strongest targets: the finest
  // levels are drawn (coarser levels average the targets away).
  const lod::Camera kCamera = lod::look_at(169.4490, -19.5308, 0, 400, 0, -90, 60, 320, 240);
};

size_t hint_coloured_pixels(const std::vector<uint8_t>& rgba) {
  const testing::Image image{0, 0, rgba};
  const HintStyle style;
  return testing::count_colour(image, style.good[0], style.good[1], style.good[2]) +
         testing::count_colour(image, style.bad[0], style.bad[1], style.bad[2]);
}

TEST_F(SceneHints, HintsAreDrawnOverTheFrameAndInteractiveFramesWaitForNone) {
  auto plain = scene(false, false);
  ASSERT_TRUE(plain) << plain.error().message;
  auto f = (*plain)->draw(kCamera, *target_);
  ASSERT_TRUE(f) << f.error().message;
  EXPECT_EQ(f->hints, 0u);
  const std::vector<uint8_t> without = *target_->read_rgba();
  EXPECT_EQ(hint_coloured_pixels(without), 0u);

  auto complete = scene(true, false);
  ASSERT_TRUE(complete) << complete.error().message;
  f = (*complete)->draw(kCamera, *target_);
  ASSERT_TRUE(f) << f.error().message;
  EXPECT_TRUE(f->complete);
  EXPECT_GT(f->hints, 0u);
  EXPECT_EQ(f->hints, (*complete)->last_hints().size());
  const std::vector<uint8_t> with = *target_->read_rgba();
  EXPECT_GT(hint_coloured_pixels(with), 20u);

  // Interactive: the first frames draw what is detected so far and are not
  // complete while tiles wait; the frames then converge to the complete one.
  // Each layer tile that arrives and each tile's hints detected are
  // announced (SceneOptions::on_change: a waiting viewer draws again).
  std::atomic<size_t> changes{0};
  auto interactive = scene(true, true, sar(), [&changes] { ++changes; });
  ASSERT_TRUE(interactive) << interactive.error().message;
  f = (*interactive)->draw(kCamera, *target_);
  ASSERT_TRUE(f) << f.error().message;
  EXPECT_FALSE(f->complete);
  for (int i = 0; i < 2000 && !f->complete; ++i) {
    std::this_thread::sleep_for(5ms);
    clock_.advance(std::chrono::milliseconds(40));
    f = (*interactive)->draw(kCamera, *target_);
    ASSERT_TRUE(f) << f.error().message;
  }
  ASSERT_TRUE(f->complete);
  EXPECT_EQ(f->hints, (*complete)->last_hints().size());
  EXPECT_EQ(*target_->read_rgba(), with);
  const size_t detected = (*interactive)->target_hints()->tiles_detected();
  EXPECT_GT(detected, 0u);
  EXPECT_GT(changes, detected) << "the detections and at least one tile load";
}

TEST_F(SceneHints, DetectionNeedsASarLayer) {
  auto none = scene(true, false, testing::pyrenees_store());
  ASSERT_FALSE(none);
  EXPECT_NE(none.error().message.find("--detect: needs a SAR texture layer"), std::string::npos)
      << none.error().message;
}

}  // namespace
}  // namespace relief::view
