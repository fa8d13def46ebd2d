// Texture layers processed on the GPU at draw time (docs/gpu-processing.md,
// "Draw-time processing"), on the bundled SAR image draped over the bare
// ellipsoid: a parameter change leaves no tile of the old parameters in the
// next interactive frame, and layers composite by opacity.
#include <gtest/gtest.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <limits>
#include <thread>

#include "../ingest/built_stores.h"
#include "../support/test_support.h"
#include "gl_scene_test.h"
#include "relief/view/scene.h"

namespace relief::view {
namespace {

using namespace std::chrono_literals;

// Straight down on the middle of the image, from 1.5 km.
const lod::Camera kDown = lod::look_at(169.4485, -19.5273, 0, 1500, 0, -90, 60, 160, 120);

// `op` then a linear mapping, parameters for the finest level.
gpuprocess::OperatorChain chain_of(const std::string& op, std::vector<std::string> params,
                                   std::vector<std::string> linear_params = {}) {
  gpuprocess::OperatorChain c;
  auto step = gpuprocess::make_step(op, params);
  EXPECT_TRUE(step) << step.error().message;
  if (step) c.steps.push_back(*step);
  auto linear = gpuprocess::make_step("linear", linear_params);
  EXPECT_TRUE(linear) << linear.error().message;
  if (linear) c.steps.push_back(*linear);
  return c;
}

// On the GPU unless told (ProcessOn::automatic would be the CPU on llvmpipe).
render::TextureLayer layer(gpuprocess::OperatorChain chain, float opacity = 1,
                           gpuprocess::ColorMap map = gpuprocess::ColorMap::grey,
                           render::ProcessOn where = render::ProcessOn::gpu) {
  render::TextureLayer l;
  l.store = &sar();
  l.process_on = where;
  if (chain.steps.empty()) l.range_max = 100;  // raw amplitudes; a mapping gives [0, 1]
  l.chain = std::move(chain);
  l.opacity = opacity;
  l.colormap = map;
  return l;
}

class TextureLayersTest : public GlSceneTest {
 protected:
  void SetUp() override { set_up_gl(kDown.width, kDown.height_px); }

  // A scene of `layers` on the bare ellipsoid (no elevation store).
  std::unique_ptr<Scene> scene(std::vector<render::TextureLayer> layers, bool interactive) {
    SceneOptions o;
    o.interactive = interactive;
    // Frames stepped deterministically: no wall-clock budget on processing.
    o.render.processing_per_frame = std::numeric_limits<double>::infinity();
    o.texture_layers = std::move(layers);
    o.selection.texture = &sar();
    auto s = Scene::create(nullptr, nullptr, o, clock_);
    EXPECT_TRUE(s) << s.error().message;
    return s ? std::move(*s) : nullptr;
  }

  // The complete still of `layers`.
  std::vector<uint8_t> still(std::vector<render::TextureLayer> layers) {
    auto s = scene(std::move(layers), false);
    if (!s) return {};
    auto f = s->draw(kDown, *target_);
    EXPECT_TRUE(f) << f.error().message;
    if (f) {
      EXPECT_TRUE(f->complete);
    }
    auto pixels = target_->read_rgba();
    EXPECT_TRUE(pixels) << pixels.error().message;
    return pixels ? *pixels : std::vector<uint8_t>{};
  }

  // Interactive frames until one is complete (every layer tile resident and
  // processed; tiles load on the loaders' threads meanwhile), at most 200.
  bool draw_until_complete(Scene& s) {
    for (int frame = 0; frame < 200; ++frame) {
      auto f = s.draw(kDown, *target_);
      EXPECT_TRUE(f) << f.error().message;
      if (!f) return false;
      if (f->complete) return true;
      std::this_thread::sleep_for(5ms);
    }
    return false;
  }
};

TEST_F(TextureLayersTest, AParameterChangeLeavesNoStaleTileInTheNextFrame) {
  // Masks keep their size on the ground: at this view's levels a Lee radius
  // of a few finest samples is below one sample; the mapping's parameter
  // changes every sample.
  auto s = scene({layer(chain_of("lee", {"radius=3"}, {"sigmas=3"}))}, true);
  ASSERT_TRUE(s);
  ASSERT_TRUE(draw_until_complete(*s));
  const std::vector<uint8_t> before = *target_->read_rgba();
  auto again = s->draw(kDown, *target_);
  ASSERT_TRUE(again);
  EXPECT_EQ(again->draw.layer_tiles_processed, 0u) << "cached composites are drawn again";

  ASSERT_TRUE(s->set_texture_layers({layer(chain_of("lee", {"radius=3"}, {"sigmas=1.5"}))}));
  auto next = s->draw(kDown, *target_);
  ASSERT_TRUE(next) << next.error().message;
  EXPECT_TRUE(next->complete);
  EXPECT_GT(next->draw.layer_tiles_processed, 0u);
  EXPECT_GT(next->draw.processing_seconds, 0.0);
  const std::vector<uint8_t> after = *target_->read_rgba();
  EXPECT_NE(after, before) << "the new parameters change the image";
  // Every tile of the next frame has the new parameters: it is the still of them.
  EXPECT_EQ(after, still({layer(chain_of("lee", {"radius=3"}, {"sigmas=1.5"}))}));
}

// The largest difference between two frames' channels.
int largest_difference(const std::vector<uint8_t>& a, const std::vector<uint8_t>& b) {
  int largest = a.size() == b.size() ? 0 : 256;
  for (size_t i = 0; i < a.size() && i < b.size(); ++i) {
    largest = std::max(largest, std::abs(int(a[i]) - int(b[i])));
  }
  return largest;
}

// --process-on cpu: the chain runs on worker threads, which a frame waits
// for only within its processing budget (without one here: the first frame
// waits for them); frames after a change show no tile of the old parameters
// (a quad shows its new composite, an ancestor's, or none), and the complete frame equals
// the GPU's still within a grey level (the linear mapping's division: double
// on the CPU, float on the GPU). The change also turns the grey map into
// viridis, so an old, grey pixel cannot pass for a new one.
TEST_F(TextureLayersTest, OnTheCpuAParameterChangeLeavesNoStaleTileAndEqualsTheGpu) {
  const auto cpu = render::ProcessOn::cpu;
  using gpuprocess::ColorMap;
  auto s =
      scene({layer(chain_of("lee", {"radius=3"}, {"sigmas=3"}), 1, ColorMap::grey, cpu)}, true);
  ASSERT_TRUE(s);
  // Frames until complete; with `old`, none may show one of its grey pixels
  // where the bare ground is not that colour.
  auto until_complete = [&](const std::vector<uint8_t>& old, const std::vector<uint8_t>& ground) {
    for (int frame = 0; frame < 400; ++frame) {
      auto f = s->draw(kDown, *target_);
      EXPECT_TRUE(f) << f.error().message;
      if (!f) return false;
      const std::vector<uint8_t> pixels = *target_->read_rgba();
      for (size_t i = 0; i < pixels.size() && !old.empty(); i += 4) {
        const bool grey = pixels[i] == pixels[i + 1] && pixels[i] == pixels[i + 2];
        const bool stale = grey && std::equal(&pixels[i], &pixels[i] + 3, &old[i]) &&
                           !std::equal(&pixels[i], &pixels[i] + 3, &ground[i]);
        if (stale) {
          ADD_FAILURE() << "frame " << frame << ": pixel " << i / 4 << " has the old parameters";
          return false;
        }
      }
      if (f->complete) return true;
      std::this_thread::sleep_for(5ms);
    }
    return false;
  };
  const auto gpu_before = still({layer(chain_of("lee", {"radius=3"}, {"sigmas=3"}))});
  ASSERT_TRUE(until_complete({}, {}));
  const std::vector<uint8_t> before = *target_->read_rgba();
  EXPECT_LE(largest_difference(before, gpu_before), 1);

  const auto changed = chain_of("lee", {"radius=3"}, {"sigmas=1.5"});
  const auto gpu_after = still({layer(changed, 1, ColorMap::viridis)});
  const auto ground = still({layer({}, 0)});
  ASSERT_TRUE(s->set_texture_layers({layer(changed, 1, ColorMap::viridis, cpu)}));
  ASSERT_TRUE(until_complete(before, ground));
  EXPECT_LE(largest_difference(*target_->read_rgba(), gpu_after), 1);
}

// --process-on cpu, a change whose processing fits the frame's budget (here
// none: frames stepped deterministically): the next frame waits for the
// workers (processing is not I/O) and is complete, every tile of the new
// parameters, their colours mapped on the CPU (within a grey level of the
// GPU's still). Before, it only submitted the jobs and showed ancestors.
TEST_F(TextureLayersTest, OnTheCpuAChangeThatFitsTheBudgetIsCompleteInTheNextFrame) {
  const auto cpu = render::ProcessOn::cpu;
  auto s = scene(
      {layer(chain_of("lee", {"radius=3"}, {"sigmas=3"}), 1, gpuprocess::ColorMap::grey, cpu)},
      true);
  ASSERT_TRUE(s);
  ASSERT_TRUE(draw_until_complete(*s));
  const auto changed = chain_of("lee", {"radius=3"}, {"sigmas=1.5"});
  ASSERT_TRUE(s->set_texture_layers({layer(changed, 1, gpuprocess::ColorMap::grey, cpu)}));
  auto next = s->draw(kDown, *target_);
  ASSERT_TRUE(next) << next.error().message;
  EXPECT_TRUE(next->complete);
  EXPECT_GT(next->draw.layer_tiles_processed, 0u);
  EXPECT_EQ(next->draw.texture_misses, 0u);
  EXPECT_LE(largest_difference(*target_->read_rgba(), still({layer(changed)})), 1);
}

TEST_F(TextureLayersTest, LayersCompositeByOpacity) {
  const auto grey = layer({}, 1);
  const auto filtered = layer(chain_of("lee", {"radius=2"}), 1, gpuprocess::ColorMap::viridis);
  const std::vector<uint8_t> a = still({grey}), b = still({filtered});
  auto transparent = grey;
  transparent.opacity = 0;
  const std::vector<uint8_t> ground = still({transparent});
  auto half_a = grey, half_b = filtered;
  half_a.opacity = half_b.opacity = 0.5f;
  const std::vector<uint8_t> both = still({half_a, half_b});
  ASSERT_EQ(both.size(), a.size());
  // The terrain shader on the bare ellipsoid (shaders.h): flat, so the light
  // is mix(0.35 + 0.65 s, 0.75 + 0.25 s, alpha) with s = cos 45 degrees.
  const double s = std::sqrt(0.5), l0 = 0.35 + 0.65 * s, l1 = 0.75 + 0.25 * s;
  int probed = 0;
  for (int y = 40; y < 80; y += 13) {
    for (int x = 60; x < 100; x += 13) {
      for (int c = 0; c < 3; ++c) {
        const size_t i = (static_cast<size_t>(y) * kDown.width + x) * 4 + c;
        // Bottom layer a at 0.5, then b over it at 0.5: alpha 0.75.
        const double ga = a[i] / 255.0 / l1, gb = b[i] / 255.0 / l1, g0 = ground[i] / 255.0 / l0;
        const double expected = (0.25 * g0 + 0.25 * ga + 0.5 * gb) * (0.25 * l0 + 0.75 * l1);
        EXPECT_NEAR(both[i] / 255.0, expected, 3.0 / 255) << x << "," << y << " channel " << c;
        ++probed;
      }
      const size_t i = (static_cast<size_t>(y) * kDown.width + x) * 4;
      EXPECT_NE(a[i + 1], b[i + 1]) << "the layers differ where probed";
    }
  }
  EXPECT_GT(probed, 0);
}

TEST_F(TextureLayersTest, ALensProcessesItsCircleWithItsOwnChain) {
  // Global: linear over mean + 3 std; inside a 200 m lens at the view's
  // centre: over mean + 1 std (brighter). Samples are merged one by one.
  auto global = layer(chain_of("lee", {"radius=1"}, {"sigmas=3"}));
  auto lens_chain = chain_of("lee", {"radius=1"}, {"sigmas=1"});
  auto with_lens = global;
  with_lens.lenses.push_back({kDown.lon, kDown.lat, 200, lens_chain});
  const std::vector<uint8_t> outside = still({global}), inside = still({layer(lens_chain)}),
                             lensed = still({with_lens});
  ASSERT_EQ(lensed.size(), outside.size());
  // Straight down: pixel distances from the centre, times the ground size of a pixel.
  const double metres_per_pixel =
      2 * kDown.height * std::tan(kDown.fov_y / 2 * M_PI / 180) / kDown.height_px;
  size_t in = 0, out = 0;
  for (int y = 0; y < kDown.height_px; ++y) {
    for (int x = 0; x < kDown.width; ++x) {
      const double r = std::hypot(x + 0.5 - kDown.width / 2.0, y + 0.5 - kDown.height_px / 2.0) *
                       metres_per_pixel;
      const size_t i = (static_cast<size_t>(y) * kDown.width + x) * 4;
      if (r < 170) {
        EXPECT_EQ(lensed[i], inside[i]) << x << "," << y;
        in += inside[i] != outside[i];
      } else if (r > 230) {
        EXPECT_EQ(lensed[i], outside[i]) << x << "," << y;
        ++out;
      }
    }
  }
  EXPECT_GT(in, 100u) << "the chains differ inside the lens";
  EXPECT_GT(out, 1000u);
}

TEST_F(TextureLayersTest, BadLayersAreOneLineErrors) {
  auto bad = layer({}, 1.5f);
  SceneOptions o;
  o.texture_layers = {bad};
  auto s = Scene::create(nullptr, nullptr, o, clock_);
  ASSERT_FALSE(s);
  EXPECT_NE(s.error().message.find("opacity"), std::string::npos) << s.error().message;
  auto wide = layer(chain_of("mean", {"radius=9"}));
  o.texture_layers = {wide};
  s = Scene::create(nullptr, nullptr, o, clock_);
  ASSERT_FALSE(s);
  EXPECT_NE(s.error().message.find("border"), std::string::npos) << s.error().message;
  auto lens = layer({});
  lens.lenses.push_back({kDown.lon, kDown.lat, 0, {}});
  o.texture_layers = {lens};
  s = Scene::create(nullptr, nullptr, o, clock_);
  ASSERT_FALSE(s);
  EXPECT_NE(s.error().message.find("lens radius"), std::string::npos) << s.error().message;
  // A changed layer is checked too, and the scene keeps its old parameters.
  auto good = scene({layer({})}, false);
  ASSERT_TRUE(good);
  auto st = good->set_texture_layers({layer({}, -1)});
  ASSERT_FALSE(st);
  EXPECT_EQ(st.error().message.find('\n'), std::string::npos);
}

}  // namespace
}  // namespace relief::view
