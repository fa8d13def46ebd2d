// The frame loop as a library, stepped frame by frame on a ManualClock:
// interactive frames never wait (the first draws level 0 only) and converge
// to the complete frame of the same camera, pixel for pixel; a path plays one
// frame per 1/fps of clock time, reports its cut and when the view after it
// was complete.
#include <gtest/gtest.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdint>
#include <functional>
#include <optional>
#include <string>
#include <thread>
#include <tuple>

#include "../ingest/built_stores.h"
#include "../support/test_support.h"
#include "relief/base/manual_clock.h"
#include "relief/pipeline/fused_elevation.h"
#include "relief/view/path_player.h"

namespace relief::view {
namespace {

using namespace std::chrono_literals;

const lod::Camera kOblique = lod::look_at(1.5, 42.5, 1500, 30000, 20, -35, 60, 160, 120);

class SceneTest : public ::testing::Test {
 protected:
  void SetUp() override {
    auto context = render::GlContext::create_headless();
    ASSERT_TRUE(context) << context.error().message;
    context_ = std::move(*context);
    auto target = render::make_offscreen_target(kOblique.width, kOblique.height_px);
    ASSERT_TRUE(target) << target.error().message;
    target_ = std::move(*target);
  }

  std::unique_ptr<Scene> scene(bool interactive, lod::LodMode mode = lod::LodMode::edge_marks,
                               const tiles::Store* store = nullptr,
                               uint32_t uploads_per_frame = 0) {
    SceneOptions o;
    o.interactive = interactive;
    o.uploads_per_frame = uploads_per_frame;
    o.selection.mode = mode;
    o.mesh_level = 3;
    auto s = Scene::create(store ? *store : testing::pyrenees_store(), nullptr, o, clock_);
    EXPECT_TRUE(s) << s.error().message;
    return s ? std::move(*s) : nullptr;
  }

  static void wait_idle(Scene& s) {
    for (int i = 0; i < 60000 && !s.elevation_loader()->idle(); ++i) {
      std::this_thread::sleep_for(1ms);
    }
    ASSERT_TRUE(s.elevation_loader()->idle());
  }

  // Interactive frames of `camera` until one is complete (64 at most, the
  // loaders idle between frames): the last frame, and the data tiles whose
  // diamond errors the frames measured on the render thread or found
  // prepared by the loaders' threads. `each` sees every frame.
  struct Converged {
    std::optional<FrameReport> last;
    uint64_t measured = 0, prepared = 0;
  };
  Converged draw_until_complete(Scene& s, const lod::Camera& camera,
                                const std::function<void(const FrameReport&)>& each = {}) {
    Converged c;
    for (int frame = 0; frame < 64 && !(c.last && c.last->complete); ++frame) {
      if (frame > 0) wait_idle(s);
      auto f = s.draw(camera, *target_);
      EXPECT_TRUE(f) << (f ? std::string() : f.error().message);
      if (!f) break;
      if (f->refine) {
        c.measured += f->refine->tiles_measured;
        c.prepared += f->refine->tiles_prepared;
      }
      if (each) each(*f);
      c.last = *f;
    }
    return c;
  }

  ManualClock clock_;
  std::unique_ptr<render::GlContext> context_;
  std::unique_ptr<render::RenderTarget> target_;
};

TEST_F(SceneTest, InteractiveFramesNeverWaitAndConvergeToTheCompleteFrame) {
  for (const lod::LodMode mode : {lod::LodMode::edge_marks, lod::LodMode::quads}) {
    SCOPED_TRACE(mode == lod::LodMode::quads ? "quads" : "edge marks");
    auto complete = scene(false, mode);
    ASSERT_TRUE(complete);
    auto still = complete->draw(kOblique, *target_);
    ASSERT_TRUE(still) << still.error().message;
    EXPECT_TRUE(still->complete);
    const std::vector<uint8_t> expected = *target_->read_rgba();

    // SceneOptions::uploads_per_frame: with a budget, no frame uploads more
    // new tiles than it allows (the first also its root tile); quads that
    // would need more stay whole, and such a frame is not complete and draws
    // more. The frames converge to the complete frame all the same.
    for (const uint32_t budget : {0u, 3u}) {
      SCOPED_TRACE(std::to_string(budget) + " uploads per frame");
      auto live = scene(true, mode, nullptr, budget);
      ASSERT_TRUE(live);
      auto first = live->draw(kOblique, *target_);
      ASSERT_TRUE(first) << first.error().message;
      EXPECT_FALSE(first->complete);  // only level 0 was resident: the rest was requested
      EXPECT_GT(first->selection.waiting, 0u);
      EXPECT_LE(first->draw.uploads, budget ? budget + 1 : UINT32_MAX);
      std::optional<FrameReport> last;
      int deferring = 0;
      for (int frame = 0; frame < 64 && !(last && last->complete); ++frame) {
        wait_idle(*live);
        auto f = live->draw(kOblique, *target_);
        ASSERT_TRUE(f) << f.error().message;
        EXPECT_LE(f->draw.uploads, budget ? budget : UINT32_MAX);
        if (f->selection.deferred > 0) {
          ++deferring;
          EXPECT_FALSE(f->complete);
          EXPECT_TRUE(f->draws_more);
        }
        last = *f;
      }
      EXPECT_EQ(deferring > 0, budget > 0);  // the budget held splits back
      ASSERT_TRUE(last && last->complete);
      EXPECT_EQ(*target_->read_rgba(), expected);
      EXPECT_EQ(last->selection.quads, still->selection.quads);
      EXPECT_EQ(last->draw.triangles, still->draw.triangles);
      EXPECT_EQ(last->refine.has_value(), mode == lod::LodMode::edge_marks);
    }
    // Measured on the drawn mesh, within the threshold (1 px). (The complete
    // frame's scene may read tiles to tell covered samples from nodata; an
    // interactive one leaves out tiles with nodata rather than wait.)
    auto measured = complete->measure_last_frame(kOblique, 4000);
    ASSERT_TRUE(measured) << measured.error().message;
    EXPECT_GT(measured->samples, 200u);
    EXPECT_LE(measured->max_pixels, 1.0);
  }
}

// The last frame measured at given data points (bench/web measures another
// client's frame at the same points): the store's finest samples around the
// view's target are drawn within the threshold; a point 3000 m above its
// sample is pixels off; a point outside the view or without a height has
// no figure.
TEST_F(SceneTest, TheLastFrameIsMeasuredAtGivenDataPoints) {
  const tiles::Store& store = testing::pyrenees_store();
  const int finest = store.manifest().max_level;
  const int w = store.grid().width(), h = store.grid().height(), b = store.grid().border();
  const double n = std::ldexp(1.0, finest);
  std::vector<lod::DataPoint> points;
  for (int i = -5; i <= 5; ++i) {
    for (int j = -5; j <= 5; ++j) {
      const double lon = 1.5 + i * 0.004, lat = 42.5 + j * 0.004;
      const geo::TileKey k{finest, static_cast<uint32_t>((lon + 180) / 360 * n),
                           static_cast<uint32_t>((90 - lat) / 180 * n)};
      const geo::GeoBox kb = k.bounds();
      const int x = static_cast<int>((lon - kb.west) / kb.width() * w);
      const int y = static_cast<int>((kb.north - lat) / kb.height() * h);
      auto tile = store.read_tile(k);
      ASSERT_TRUE(tile) << tile.error().message;
      const tiles::Raster& r = tile->raster;
      const float height =
          r.f32()[static_cast<size_t>(y + b) * r.width() + static_cast<size_t>(x + b)];
      if (std::isnan(height)) continue;  // a void of the data
      points.push_back(
          {kb.west + (x + 0.5) * kb.width() / w, kb.north - (y + 0.5) * kb.height() / h, height});
    }
  }
  for (const lod::LodMode mode : {lod::LodMode::edge_marks, lod::LodMode::quads}) {
    SCOPED_TRACE(mode == lod::LodMode::quads ? "quads" : "edge marks");
    auto complete = scene(false, mode);
    ASSERT_TRUE(complete);
    auto still = complete->draw(kOblique, *target_);
    ASSERT_TRUE(still && still->complete);
    std::vector<lod::DataPoint> all = points;
    all.push_back({points[0].lon, points[0].lat, points[0].height + 3000});
    all.push_back({1.5, 41.2, 500});                     // behind the camera, south of it
    all.push_back({points[0].lon, points[0].lat, NAN});  // nodata
    auto pixels = complete->measure_last_frame_at(kOblique, all);
    ASSERT_TRUE(pixels) << pixels.error().message;
    ASSERT_EQ(pixels->size(), all.size());
    size_t measured = 0;
    for (size_t i = 0; i < points.size(); ++i) {
      if (!(*pixels)[i]) continue;
      ++measured;
      EXPECT_LE(*(*pixels)[i], 1.0) << points[i].lon << "," << points[i].lat;
    }
    EXPECT_GT(measured, points.size() * 9 / 10);
    ASSERT_TRUE((*pixels)[points.size()]);
    EXPECT_GT(*(*pixels)[points.size()], 2.0);
    EXPECT_FALSE((*pixels)[points.size() + 1]);
    EXPECT_FALSE((*pixels)[points.size() + 2]);
  }
}

// The per-diamond errors of the tiles interactive frames refine were all
// measured by the loader's threads (or at creation, level 0), none in a
// frame, and the refined mesh is the one a complete frame measures inline.
TEST_F(SceneTest, InteractiveFramesRefineWithDiamondErrorsPreparedOffTheRenderThread) {
  auto live = scene(true);
  ASSERT_TRUE(live);
  const Converged c = draw_until_complete(*live, kOblique);
  ASSERT_TRUE(c.last && c.last->complete && c.last->refine);
  EXPECT_EQ(c.measured, 0u);
  EXPECT_GT(c.prepared, 4u);  // level 0 and the tiles of the frames that followed
  EXPECT_LE(c.prepared, c.last->refine_cache_tiles);

  auto complete = scene(false);
  ASSERT_TRUE(complete);
  auto still = complete->draw(kOblique, *target_);
  ASSERT_TRUE(still) << still.error().message;
  EXPECT_GT(still->refine->tiles_measured, 0u);  // inline
  EXPECT_EQ(still->refine->tiles_prepared, 0u);
  ASSERT_TRUE(live->last_refined() && complete->last_refined());
  EXPECT_EQ(live->last_selection().quads.size(), complete->last_selection().quads.size());
  // The same mesh (the live scene may reuse decisions of its earlier frames:
  // lod::RefineHistory, so not the same count of criteria evaluated).
  EXPECT_EQ(live->last_refined()->indices, complete->last_refined()->indices);
  EXPECT_GT(live->last_refined()->stats.marks_evaluated + live->last_refined()->stats.marks_reused,
            0u);
}

// Diamond errors cost about four times their tile's decoded heights, so the
// errors' budget fills long before the loader's: the tiles whose errors were
// evicted are forgotten by the loader, and a view that returns to them loads
// them again and has the loader's threads prepare them, instead of the
// render thread measuring tiles still resident (up to 100 ms a frame for
// four tiles over the Himalaya).
TEST_F(SceneTest, TilesWhoseDiamondErrorsWereEvictedLoadAgainInsteadOfBeingMeasured) {
  SceneOptions o;
  o.interactive = true;
  o.selection.mode = lod::LodMode::edge_marks;
  o.loader.memory_budget = uint64_t{32} << 20;
  auto created = Scene::create(testing::pyrenees_store(), nullptr, o, clock_);
  ASSERT_TRUE(created) << created.error().message;
  Scene& live = **created;
  const lod::Camera elsewhere = lod::look_at(1.3, 41.4, 800, 20000, 200, -40, 60, 160, 120);
  uint64_t measured = 0;
  for (const lod::Camera& camera : {kOblique, elsewhere, kOblique}) {
    const Converged c = draw_until_complete(live, camera);
    ASSERT_TRUE(c.last && c.last->complete && c.last->refine);
    measured += c.measured;
  }
  EXPECT_EQ(measured, 0u);
  EXPECT_GT(live.elevation_loader()->stats().evicted, 0u);  // forgotten with their errors
}

// The loader's threads of an edge-mark scene measure the diamond errors, not
// the quads' exact errors, which only the quad mode's selection asks for: a
// frame that asks measures them itself; a quad-mode scene finds them prepared.
TEST_F(SceneTest, EdgeMarkScenesLeaveTheQuadsExactErrorsToWhoeverAsks) {
  for (const lod::LodMode mode : {lod::LodMode::edge_marks, lod::LodMode::quads}) {
    SCOPED_TRACE(mode == lod::LodMode::quads ? "quads" : "edge marks");
    auto live = scene(true, mode);
    ASSERT_TRUE(live);
    const std::optional<FrameReport> last = draw_until_complete(*live, kOblique).last;
    ASSERT_TRUE(last && last->complete);
    lod::TerrainModel& terrain = live->terrain();
    if (mode == lod::LodMode::quads) {
      EXPECT_GT(terrain.error_counts().prepared, 0u);  // (level 0, read at creation: inline)
      continue;
    }
    EXPECT_EQ(terrain.error_counts().prepared + terrain.error_counts().measured, 0u);
    // A drawn quad of the store's finest level, its tile and its parent's resident.
    std::optional<geo::TileKey> key;
    for (const lod::SelectedQuad& q : live->last_selection().quads) {
      if (q.key.level == terrain.data_max_level() && terrain.available(q.key) &&
          terrain.available(*q.key.parent())) {
        key = q.key;
        break;
      }
    }
    ASSERT_TRUE(key);
    auto info = terrain.quad(*key);
    ASSERT_TRUE(info) << info.error().message;
    auto error = terrain.quad_error(*key, **info);
    ASSERT_TRUE(error) << error.error().message;
    EXPECT_EQ(terrain.error_counts().prepared, 0u);
    EXPECT_EQ(terrain.error_counts().measured, 1u);
  }
}

// Elevation layers fused at draw time (pipeline/fused_elevation.h): the
// loader's threads fuse each tile and hand the fused raster to the
// refinement's hook, so interactive frames refine with diamond errors of the
// fused tiles and converge to the complete frame's mesh; over 42N, where the
// layers meet, that mesh is not the first layer's alone.
TEST_F(SceneTest, FusedLayersRefineWithDiamondErrorsOfTheFusedTiles) {
  auto layer = [](const std::string& name, const std::string& file) -> const tiles::Store& {
    ingest::BuildOptions o;
    o.inputs = {testing::data(file)};
    o.kind = tiles::DatasetKind::Elevation;
    return testing::built_store(name, o);
  };
  const tiles::Store& n41 = layer("n41", "srtm/N41E001.hgt.zip");
  std::vector<pipeline::ElevationLayer> layers;
  layers.push_back({"n41", n41});
  layers.push_back({"n42", layer("n42", "srtm/N42E001.hgt.zip")});
  ThreadExecutor executor;
  auto fused =
      pipeline::fuse_elevation_layers(std::move(layers), pipeline::FuseMode::First, executor);
  ASSERT_TRUE(fused) << fused.error().message;
  const lod::Camera seam = lod::look_at(1.5, 42.0, 1000, 30000, 10, -35, 60, 160, 120);

  auto live = scene(true, lod::LodMode::edge_marks, &*fused);
  ASSERT_TRUE(live);
  const Converged c = draw_until_complete(*live, seam);
  ASSERT_TRUE(c.last && c.last->complete);
  EXPECT_EQ(c.measured, 0u);
  EXPECT_GT(c.prepared, 4u);

  auto complete = scene(false, lod::LodMode::edge_marks, &*fused);
  ASSERT_TRUE(complete);
  ASSERT_TRUE(complete->draw(seam, *target_));
  ASSERT_TRUE(live->last_refined() && complete->last_refined());
  EXPECT_EQ(live->last_refined()->indices, complete->last_refined()->indices);

  auto alone = scene(false, lod::LodMode::edge_marks, &n41);
  ASSERT_TRUE(alone);
  ASSERT_TRUE(alone->draw(seam, *target_));
  EXPECT_NE(alone->last_refined()->indices, complete->last_refined()->indices);
}

// Layers of different depths (sparse depth, docs/rendering.md): a coarse
// layer three levels short, with N42E001 at its finest inside it. Interactive
// frames, which draw only resident tiles and take the quads' exact errors
// from the loader's threads, converge to the complete frame's quads, sides
// and corners; with edge marks (diamond errors prepared on the loader's
// threads), to the complete frame's refined mesh.
TEST_F(SceneTest, LayersOfDifferentDepthsConvergeToTheCompleteFrame) {
  ingest::BuildOptions fine;
  fine.inputs = {testing::data("srtm/N42E001.hgt.zip")};
  fine.kind = tiles::DatasetKind::Elevation;
  const tiles::Store& n42 = testing::built_store("n42", fine);
  ingest::BuildOptions coarse = fine;
  coarse.inputs = {testing::data("srtm/N41E001.hgt.zip"), testing::data("srtm/N42E001.hgt.zip")};
  coarse.max_level = n42.manifest().max_level - 3;
  std::vector<pipeline::ElevationLayer> layers;
  layers.push_back({"coarse", testing::built_store("pair-coarse", coarse)});
  layers.push_back({"n42", n42});
  ThreadExecutor executor;
  auto fused =
      pipeline::fuse_elevation_layers(std::move(layers), pipeline::FuseMode::First, executor);
  ASSERT_TRUE(fused) << fused.error().message;
  ASSERT_TRUE(fused->manifest().sparse_depth);
  const lod::Camera seam = lod::look_at(1.5, 42.0, 1000, 30000, 10, -35, 60, 160, 120);

  auto live = scene(true, lod::LodMode::quads, &*fused);
  ASSERT_TRUE(live);
  const std::optional<FrameReport> last = draw_until_complete(*live, seam).last;
  ASSERT_TRUE(last && last->complete);
  auto complete = scene(false, lod::LodMode::quads, &*fused);
  ASSERT_TRUE(complete);
  ASSERT_TRUE(complete->draw(seam, *target_));
  auto quads = [](const lod::Selection& s) {
    std::vector<std::tuple<geo::TileKey, int, int, int, int>> out;
    for (const lod::SelectedQuad& q : s.quads) {
      out.emplace_back(q.key, q.finer_sides, q.coarse_sides, q.parent_data_sides,
                       q.parent_data_corners);
    }
    return out;
  };
  EXPECT_EQ(quads(live->last_selection()), quads(complete->last_selection()));
  size_t by_data = 0;  // sides taking coarser data from a quad of their own level
  for (const lod::SelectedQuad& q : complete->last_selection().quads) {
    by_data += (q.parent_data_sides & ~q.coarse_sides) != 0;
  }
  EXPECT_GT(by_data, 0u);

  auto refining = scene(true, lod::LodMode::edge_marks, &*fused);
  ASSERT_TRUE(refining);
  const Converged c = draw_until_complete(*refining, seam);
  ASSERT_TRUE(c.last && c.last->complete);
  EXPECT_EQ(c.measured, 0u);
  EXPECT_GT(c.prepared, 4u);
  auto refined = scene(false, lod::LodMode::edge_marks, &*fused);
  ASSERT_TRUE(refined);
  ASSERT_TRUE(refined->draw(seam, *target_));
  EXPECT_EQ(quads(refining->last_selection()), quads(refined->last_selection()));
  ASSERT_TRUE(refining->last_refined() && refined->last_refined());
  EXPECT_EQ(refining->last_refined()->indices, refined->last_refined()->indices);
  lod::TerrainModel& terrain = refined->terrain();
  for (const lod::SelectedQuad& q : refined->last_selection().quads) {
    EXPECT_FALSE(terrain.draws_ancestor(q.key)) << q.key.to_string();
  }
}

// A selection coarser than the refinement needs (quads stop splitting when
// their level error projects to twice the threshold, not half of it): the
// quads an interactive frame's refinement wanted split, the next frame
// splits; the view is complete once nothing is wanted, and then static.
TEST_F(SceneTest, TheNextFrameSplitsTheQuadsTheRefinementWantedSplit) {
  const lod::Camera low = lod::look_at(1.6, 42.4, 1200, 15000, 200, -15, 60, 160, 120);
  SceneOptions o;
  o.mesh_level = 3;
  o.selection.mode = lod::LodMode::edge_marks;
  o.selection.level_error_share = 2.0;
  o.split_feedback = true;
  auto s = Scene::create(testing::pyrenees_store(), nullptr, o, clock_);
  ASSERT_TRUE(s) << s.error().message;
  uint32_t fed_back = 0;
  std::optional<FrameReport> last;
  for (int frame = 0; frame < 64 && !(last && last->complete); ++frame) {
    if (frame > 0) wait_idle(**s);
    auto f = (*s)->draw(low, *target_);
    ASSERT_TRUE(f) << f.error().message;
    if (f->selection.waiting == 0) {
      fed_back += static_cast<uint32_t>(f->refine->split_wanted.size());
      EXPECT_EQ(f->complete, f->refine->split_wanted.empty());
    }
    last = *f;
  }
  ASSERT_TRUE(last && last->complete);
  EXPECT_GT(fed_back, 0u);
  EXPECT_TRUE(last->refine->split_wanted.empty());
  EXPECT_EQ(last->refine->unresolved, 0u);
  EXPECT_EQ(last->refine->too_coarse, 0u);
  auto again = (*s)->draw(low, *target_);
  ASSERT_TRUE(again) << again.error().message;
  EXPECT_TRUE(again->complete);
  EXPECT_EQ(again->draw.triangles, last->draw.triangles);
  EXPECT_EQ(again->draw.geometry_bytes, 0u);
  auto measured = (*s)->measure_last_frame(low, 4000);
  ASSERT_TRUE(measured) << measured.error().message;
  EXPECT_GT(measured->samples, 100u);
  EXPECT_LE(measured->max_pixels, o.selection.pixel_error);
}

TEST_F(SceneTest, APathPlaysOneFramePerPeriodOfTheClockAndReportsItsCut) {
  auto live = scene(true);
  ASSERT_TRUE(live);
  lod::Camera far = kOblique;
  far.lon += 0.3;
  far.lat -= 0.2;
  std::vector<lod::Keyframe> keys(3);
  keys[0] = {0.0, kOblique, false};
  keys[1] = {0.5, kOblique, false};
  keys[2] = {0.55, far, true};
  keys.push_back({1.0, far, false});
  PathOptions o;
  o.fps = 10;
  o.until_complete = 30;
  clock_.set_free(true);  // sleeps jump to their deadline: frames are 0.1 s apart exactly
  std::vector<double> times;
  PathCallbacks callbacks;
  callbacks.frame_done = [&](const FrameRecord& r) -> Status {
    times.push_back(r.time);
    if (r.index >= 10) wait_idle(*live);  // after the path, let loads finish between frames
    return {};
  };
  auto summary = play_path(*live, keys, 11, o, *target_, clock_, callbacks);
  ASSERT_TRUE(summary) << summary.error().message;
  ASSERT_GE(summary->frames, 11u);
  for (size_t i = 0; i < times.size(); ++i) EXPECT_NEAR(times[i], 0.1 * i, 1e-9) << i;
  ASSERT_EQ(summary->cuts.size(), 1u);
  EXPECT_EQ(summary->cuts[0].frame, 6u);  // the first frame at t >= 0.55 s
  EXPECT_TRUE(summary->complete);
  ASSERT_TRUE(summary->cuts[0].complete_after_s);
  EXPECT_GT(*summary->cuts[0].complete_after_s, 0.0);
  EXPECT_GT(summary->drawn_bytes, 0u);
  EXPECT_GE(summary->drawn_bytes, summary->final_view_bytes / 2);
}

// The LOD panel's freeze: frames draw the last selection from a camera that
// moved (its culling and detail seen from outside) until thawed.
TEST_F(SceneTest, AFrozenSelectionIsDrawnFromTheNewCamera) {
  auto s = scene(false);
  ASSERT_TRUE(s);
  lod::Camera closer = kOblique;
  closer.lon += 0.1;
  closer.height *= 0.5;
  auto moved = s->draw(closer, *target_);
  ASSERT_TRUE(moved) << moved.error().message;
  auto still = s->draw(kOblique, *target_);
  ASSERT_TRUE(still) << still.error().message;
  const std::vector<uint8_t> image = *target_->read_rgba();
  ASSERT_NE(moved->selection.quads, still->selection.quads);  // else the test proves nothing

  s->set_selection_frozen(true);
  auto frozen = s->draw(closer, *target_);
  ASSERT_TRUE(frozen) << frozen.error().message;
  EXPECT_EQ(frozen->selection.quads, still->selection.quads);
  EXPECT_EQ(frozen->draw.triangles, still->draw.triangles);
  EXPECT_FALSE(frozen->complete);
  EXPECT_EQ(s->last_selection().quads.size(), still->selection.quads);
  auto back = s->draw(kOblique, *target_);  // the frozen selection from its own camera
  ASSERT_TRUE(back);
  EXPECT_EQ(*target_->read_rgba(), image);

  s->set_selection_frozen(false);
  auto thawed = s->draw(closer, *target_);
  ASSERT_TRUE(thawed);
  EXPECT_EQ(thawed->selection.quads, moved->selection.quads);
  EXPECT_TRUE(thawed->complete);
}

// The viewer's overlap (docs/viewer.md): draw() calls `before_drawing` once,
// after the frame's selection and refinement and before any GL call of the
// frame (the target still holds the previous frame there), and a renderer
// that does not wait for the GL (RenderOptions::finish off) draws the same
// pixels once they are read back.
TEST_F(SceneTest, BeforeDrawingComesBeforeTheFramesGlWorkAndNotWaitingDrawsTheSame) {
  lod::Camera closer = kOblique;
  closer.lon += 0.1;
  closer.height *= 0.5;
  std::vector<std::vector<uint8_t>> expected;
  SceneOptions o;
  o.interactive = false;
  o.selection.mode = lod::LodMode::edge_marks;
  o.mesh_level = 3;
  {
    auto reference = Scene::create(testing::pyrenees_store(), nullptr, o, clock_);
    ASSERT_TRUE(reference) << reference.error().message;
    for (const lod::Camera& c : {closer, kOblique}) {
      ASSERT_TRUE((*reference)->draw(c, *target_));
      expected.push_back(*target_->read_rgba());
    }
  }
  ASSERT_NE(expected[0], expected[1]);  // else the test proves nothing

  o.render.finish = false;
  auto s = Scene::create(testing::pyrenees_store(), nullptr, o, clock_);
  ASSERT_TRUE(s) << s.error().message;
  ASSERT_TRUE((*s)->draw(closer, *target_));
  EXPECT_EQ(*target_->read_rgba(), expected[0]);
  int calls = 0;
  std::vector<uint8_t> seen;
  const auto before = [&] {
    ++calls;
    seen = *target_->read_rgba();
  };
  auto frame = (*s)->draw(kOblique, *target_, before);
  ASSERT_TRUE(frame) << frame.error().message;
  EXPECT_EQ(calls, 1);
  EXPECT_EQ(seen, expected[0]) << "the frame's GL work began before before_drawing";
  ASSERT_TRUE(frame->refine);  // refined before: the report has its statistics
  EXPECT_GT(frame->refine->marks_evaluated, 0u);
  EXPECT_EQ(*target_->read_rgba(), expected[1]);

  (*s)->set_selection_frozen(true);  // frozen frames call it too
  ASSERT_TRUE((*s)->draw(closer, *target_, before));
  EXPECT_EQ(calls, 2);
  EXPECT_EQ(seen, expected[1]);
}

// The LOD panel's wireframe: the same triangles as lines, the sky between them.
TEST_F(SceneTest, WireframeDrawsTheTrianglesEdges) {
  auto s = scene(false);
  ASSERT_TRUE(s);
  const render::RenderOptions filled = s->options().render;
  auto sky_pixels = [&](const render::RenderOptions& o) {
    s->set_render_options(o);
    auto f = s->draw(kOblique, *target_);
    EXPECT_TRUE(f) << f.error().message;
    const std::vector<uint8_t> rgba = *target_->read_rgba();
    const auto to_byte = [](float c) { return static_cast<uint8_t>(std::lround(c * 255)); };
    size_t n = 0;
    for (size_t i = 0; i < rgba.size(); i += 4) {
      n += rgba[i] == to_byte(o.sky[0]) && rgba[i + 1] == to_byte(o.sky[1]) &&
           rgba[i + 2] == to_byte(o.sky[2]);
    }
    return n;
  };
  render::RenderOptions wire = filled;
  wire.wireframe = true;
  const size_t solid = sky_pixels(filled), lines = sky_pixels(wire);
  const size_t pixels =
      static_cast<size_t>(kOblique.width) * static_cast<size_t>(kOblique.height_px);
  EXPECT_LT(solid, pixels / 2);  // the oblique view is mostly ground
  EXPECT_GT(lines, solid + pixels / 10);
  EXPECT_LT(lines, pixels);              // edges were drawn
  EXPECT_EQ(sky_pixels(filled), solid);  // and it is switched off again
}

// Movie export over an interactive scene: each frame waits for its tiles
// (loaded, decoded and measured on the loaders' threads, the coming frames'
// prefetched) and is then exactly the complete scene's frame.
TEST_F(SceneTest, WaitingForCompleteFramesDrawsTheCompleteScenesFrames) {
  lod::Camera far = kOblique;
  far.lon += 0.2;
  far.height *= 0.6;
  const std::vector<lod::Keyframe> keys = {{0.0, kOblique, false}, {1.0, far, false}};
  constexpr size_t kFrames = 5;
  auto frames_of = [&](Scene& s, const PathOptions& o) {
    std::vector<std::vector<uint8_t>> images;
    PathCallbacks callbacks;
    callbacks.frame_done = [&](const FrameRecord& r) -> Status {
      EXPECT_TRUE(r.report.complete) << "frame " << r.index;
      images.push_back(RELIEF_TRY(target_->read_rgba()));
      return {};
    };
    auto summary = play_path(s, keys, kFrames, o, *target_, clock_, callbacks);
    EXPECT_TRUE(summary) << summary.error().message;
    return images;
  };
  PathOptions o;
  o.fps = 4;
  auto complete = scene(false);
  ASSERT_TRUE(complete);
  const auto expected = frames_of(*complete, o);
  ASSERT_EQ(expected.size(), kFrames);

  auto live = scene(true);
  ASSERT_TRUE(live);
  o.wait_complete = true;
  const auto frames = frames_of(*live, o);
  ASSERT_EQ(frames.size(), kFrames);
  for (size_t i = 0; i < kFrames; ++i) EXPECT_TRUE(frames[i] == expected[i]) << "frame " << i;
  const stream::LoaderStats ls = live->elevation_loader()->stats();
  EXPECT_GT(ls.prefetched, 0u) << "the coming frames' tiles were prefetched";
  EXPECT_EQ(ls.failed, 0u);
}

// The movie export's read-back: GL's bottom-up rows into a reused buffer,
// the image of read_rgba() flipped; a target without its own (the window's
// wrapper) gets the same from the default.
TEST_F(SceneTest, BottomUpReadBackIsTheImageFlipped) {
  auto s = scene(false);
  ASSERT_TRUE(s);
  ASSERT_TRUE(s->draw(kOblique, *target_));
  const std::vector<uint8_t> top_down = *target_->read_rgba();
  std::vector<uint8_t> flipped(top_down.size());
  const size_t row = static_cast<size_t>(kOblique.width) * 4;
  for (int y = 0; y < kOblique.height_px; ++y) {
    std::copy_n(&top_down[static_cast<size_t>(kOblique.height_px - 1 - y) * row], row,
                &flipped[static_cast<size_t>(y) * row]);
  }
  ASSERT_NE(flipped, top_down);  // sky above, ground below
  std::vector<uint8_t> buffer(top_down.size(), 7);
  const uint8_t* storage = buffer.data();
  ASSERT_TRUE(target_->read_rgba_bottom_up(buffer));
  EXPECT_EQ(buffer, flipped);
  EXPECT_EQ(buffer.data(), storage) << "the buffer is reused";

  struct Wrapper final : render::RenderTarget {
    render::RenderTarget& inner;
    explicit Wrapper(render::RenderTarget& t) : inner(t) {}
    int width() const override { return inner.width(); }
    int height() const override { return inner.height(); }
    void bind() override { inner.bind(); }
    Result<std::vector<uint8_t>> read_rgba() override { return inner.read_rgba(); }
  } wrapper(*target_);
  std::vector<uint8_t> by_default;
  ASSERT_TRUE(wrapper.read_rgba_bottom_up(by_default));
  EXPECT_EQ(by_default, flipped);
}

TEST(Percentile, NearestRank) {
  EXPECT_EQ(percentile({}, 0.5), 0.0);
  EXPECT_EQ(percentile({3, 1, 2}, 0.5), 2.0);
  EXPECT_EQ(percentile({3, 1, 2}, 0.0), 1.0);
  EXPECT_EQ(percentile({3, 1, 2}, 1.0), 3.0);
}

}  // namespace
}  // namespace relief::view
