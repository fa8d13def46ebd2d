#pragma once
// What the scene tests share: the SAR store, a headless GL context, an offscreen target of
// their frame's size and a manual clock (freed at the end, so the loaders'
// retry pauses end at once).
#include <gtest/gtest.h>

#include <memory>

#include "../ingest/built_stores.h"
#include "../support/test_support.h"
#include "relief/base/manual_clock.h"
#include "relief/render/render_target.h"

namespace relief::view {

// The bundled Umbra SAR image as a store, built once per test binary.
inline const tiles::Store& sar() {
  ingest::BuildOptions o;
  o.inputs = {relief::testing::data("sar/umbra_mount_yasur.tif")};
  o.kind = tiles::DatasetKind::Sar;
  return relief::testing::built_store("umbra", o);
}

class GlSceneTest : public ::testing::Test {
 protected:
  // Derived fixtures call this from SetUp() with their frame's size.
  void set_up_gl(int width, int height) {
    auto context = render::GlContext::create_headless();
    ASSERT_TRUE(context) << context.error().message;
    context_ = std::move(*context);
    auto target = render::make_offscreen_target(width, height);
    ASSERT_TRUE(target) << target.error().message;
    target_ = std::move(*target);
  }
  void TearDown() override { clock_.set_free(true); }

  ManualClock clock_;
  std::unique_ptr<render::GlContext> context_;
  std::unique_ptr<render::RenderTarget> target_;
};

}  // namespace relief::view
