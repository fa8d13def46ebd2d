#pragma once
// An interactive scene over the bundled Pyrenees store, with the tiles of a
// view loaded: what the ground and picking tests query.
#include <gtest/gtest.h>

#include <chrono>
#include <thread>

#include "../ingest/built_stores.h"
#include "relief/base/manual_clock.h"
#include "relief/view/scene.h"

namespace relief::view::testing {

class LoadedSceneTest : public ::testing::Test {
 protected:
  void SetUp() override {
    auto context = render::GlContext::create_headless();
    ASSERT_TRUE(context) << context.error().message;
    context_ = std::move(*context);
    auto target = render::make_offscreen_target(160, 120);
    ASSERT_TRUE(target) << target.error().message;
    target_ = std::move(*target);
    SceneOptions o;
    o.mesh_level = 3;
    auto s = Scene::create(relief::testing::pyrenees_store(), nullptr, o, clock_);
    ASSERT_TRUE(s) << s.error().message;
    scene_ = std::move(*s);
  }
  void TearDown() override {
    clock_.set_free(true);  // the loaders' retry pauses end at once
    scene_.reset();
  }

  void wait_idle() {
    using namespace std::chrono_literals;
    for (int i = 0; i < 60000 && !scene_->elevation_loader()->idle(); ++i) {
      std::this_thread::sleep_for(1ms);
    }
    ASSERT_TRUE(scene_->elevation_loader()->idle());
  }
  // Draws `camera` until its frame is complete, letting loads finish between frames.
  void load(const lod::Camera& camera) {
    for (int frame = 0; frame < 64; ++frame) {
      auto f = scene_->draw(camera, *target_);
      ASSERT_TRUE(f) << f.error().message;
      if (f->complete) return;
      wait_idle();
    }
    FAIL() << "the view never completed";
  }
  // One frame of `camera` (loads go on meanwhile).
  void draw(const lod::Camera& camera) {
    auto f = scene_->draw(camera, *target_);
    ASSERT_TRUE(f) << f.error().message;
  }

  ManualClock clock_;
  std::unique_ptr<render::GlContext> context_;
  std::unique_ptr<render::RenderTarget> target_;
  std::unique_ptr<Scene> scene_;
};

}  // namespace relief::view::testing
