// The frame loop as a library, stepped frame by frame on a ManualClock:
// interactive frames never wait (the first draws level 0 only) and converge
// to the complete frame of the same camera, pixel for pixel; a path plays one
// frame per 1/fps of clock time, reports its cut and when the view after it
// was complete.
#include <gtest/gtest.h>

#include <chrono>
#include <thread>

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
                               const tiles::Store* store = nullptr) {
    SceneOptions o;
    o.interactive = interactive;
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

    auto live = scene(true, mode);
    ASSERT_TRUE(live);
    auto first = live->draw(kOblique, *target_);
    ASSERT_TRUE(first) << first.error().message;
    EXPECT_FALSE(first->complete);  // only level 0 was resident: the rest was requested
    EXPECT_GT(first->selection.waiting, 0u);
    std::optional<FrameReport> last;
    for (int frame = 0; frame < 64 && !(last && last->complete); ++frame) {
      wait_idle(*live);
      auto f = live->draw(kOblique, *target_);
      ASSERT_TRUE(f) << f.error().message;
      last = *f;
    }
    ASSERT_TRUE(last && last->complete);
    EXPECT_EQ(*target_->read_rgba(), expected);
    EXPECT_EQ(last->selection.quads, still->selection.quads);
    EXPECT_EQ(last->draw.triangles, still->draw.triangles);
    EXPECT_EQ(last->refine.has_value(), mode == lod::LodMode::edge_marks);
    // Measured on the drawn mesh, within the threshold (1 px). (The complete
    // frame's scene may read tiles to tell covered samples from nodata; an
    // interactive one leaves out tiles with nodata rather than wait.)
    auto measured = complete->measure_last_frame(kOblique, 4000);
    ASSERT_TRUE(measured) << measured.error().message;
    EXPECT_GT(measured->samples, 200u);
    EXPECT_LE(measured->max_pixels, 1.0);
  }
}

// The per-diamond errors of the tiles interactive frames refine were all
// measured by the loader's threads (or at creation, level 0), none in a
// frame, and the refined mesh is the one a complete frame measures inline.
TEST_F(SceneTest, InteractiveFramesRefineWithDiamondErrorsPreparedOffTheRenderThread) {
  auto live = scene(true);
  ASSERT_TRUE(live);
  uint64_t measured = 0, prepared = 0;
  std::optional<FrameReport> last;
  for (int frame = 0; frame < 64 && !(last && last->complete); ++frame) {
    if (frame > 0) wait_idle(*live);
    auto f = live->draw(kOblique, *target_);
    ASSERT_TRUE(f) << f.error().message;
    ASSERT_TRUE(f->refine);
    measured += f->refine->tiles_measured;
    prepared += f->refine->tiles_prepared;
    last = *f;
  }
  ASSERT_TRUE(last && last->complete);
  EXPECT_EQ(measured, 0u);
  EXPECT_GT(prepared, 4u);  // level 0 and the tiles of the frames that followed
  EXPECT_LE(prepared, last->refine_cache_tiles);

  auto complete = scene(false);
  ASSERT_TRUE(complete);
  auto still = complete->draw(kOblique, *target_);
  ASSERT_TRUE(still) << still.error().message;
  EXPECT_GT(still->refine->tiles_measured, 0u);  // inline
  EXPECT_EQ(still->refine->tiles_prepared, 0u);
  ASSERT_TRUE(live->last_refined() && complete->last_refined());
  EXPECT_EQ(live->last_selection().quads.size(), complete->last_selection().quads.size());
  EXPECT_EQ(live->last_refined()->indices, complete->last_refined()->indices);
  EXPECT_EQ(live->last_refined()->stats.marks_evaluated,
            complete->last_refined()->stats.marks_evaluated);
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
  uint64_t measured = 0, prepared = 0;
  std::optional<FrameReport> last;
  for (int frame = 0; frame < 64 && !(last && last->complete); ++frame) {
    if (frame > 0) wait_idle(*live);
    auto f = live->draw(seam, *target_);
    ASSERT_TRUE(f) << f.error().message;
    measured += f->refine->tiles_measured;
    prepared += f->refine->tiles_prepared;
    last = *f;
  }
  ASSERT_TRUE(last && last->complete);
  EXPECT_EQ(measured, 0u);
  EXPECT_GT(prepared, 4u);

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

TEST(Percentile, NearestRank) {
  EXPECT_EQ(percentile({}, 0.5), 0.0);
  EXPECT_EQ(percentile({3, 1, 2}, 0.5), 2.0);
  EXPECT_EQ(percentile({3, 1, 2}, 0.0), 1.0);
  EXPECT_EQ(percentile({3, 1, 2}, 1.0), 3.0);
}

}  // namespace
}  // namespace relief::view
