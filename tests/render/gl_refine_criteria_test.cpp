// Edge-mark refinement with its split criteria evaluated by the GL compute
// shader (render::GlRefineCriteria) on real terrain: the mesh of the CPU
// refinement, bit for bit, with few diamonds left to the CPU.
#include <gtest/gtest.h>

#include "../lod/refine_fixtures.h"
#include "relief/lod/criterion_evaluator.h"
#include "relief/render/gl_refine_criteria.h"
#include "relief/render/terrain_renderer.h"

namespace relief::render {
namespace {

using namespace relief::lod::testing;

GlRefineCriteria& criteria() {
  static std::unique_ptr<GlContext> context = [] {
    auto c = GlContext::create_headless();
    if (!c) throw std::runtime_error(c.error().message);
    return std::move(*c);
  }();
  static std::unique_ptr<GlRefineCriteria> criteria = [] {
    auto c = GlRefineCriteria::create();
    if (!c) throw std::runtime_error(c.error().message);
    return std::move(*c);
  }();
  return *criteria;
}

lod::RefinedMesh refined_on_gpu(Terrain& t, const lod::View& view, const lod::Selection& s,
                                double pixel_error, lod::RefineVariant variant) {
  lod::RefineOptions o;
  o.pixel_error = pixel_error;
  o.variant = variant;
  o.cache = &t.cache;
  o.criteria = &criteria();
  auto mesh = lod::refine(view, t.terrain, s, o);
  EXPECT_TRUE(mesh) << mesh.error().message;
  return mesh ? std::move(*mesh) : lod::RefinedMesh{};
}

TEST(GlRefineCriteria, GiveTheMeshOfTheCpuRefinement) {
  for (const char* name : {"down", "scotland", "grazing"}) {
    SCOPED_TRACE(name);
    const Case& c = case_named(name);
    Terrain& t = c.terrain();
    auto view = lod::make_view(c.camera);
    ASSERT_TRUE(view);
    const lod::Selection s = select(t, *view, c.pixel_error);
    for (double pixel_error : {c.pixel_error, 4 * c.pixel_error}) {
      const lod::RefinedMesh cpu = refined(t, *view, s, pixel_error, lod::RefineVariant::kTopDown);
      for (auto variant : {lod::RefineVariant::kBottomUp, lod::RefineVariant::kTopDown}) {
        const lod::RefinedMesh gpu = refined_on_gpu(t, *view, s, pixel_error, variant);
        EXPECT_GT(cpu.triangles(), 8 * s.quads.size());
        EXPECT_EQ(gpu.indices, cpu.indices);
        EXPECT_EQ(gpu.stats.unresolved, cpu.stats.unresolved);
        // Nearly every criterion decided on the GPU: a shader computing
        // something else would leave many near the threshold or change the mesh.
        EXPECT_GT(gpu.stats.marks_evaluated, 0u);
        EXPECT_LE(gpu.stats.marks_near * 1000, gpu.stats.marks_evaluated)
            << gpu.stats.marks_near << " of " << gpu.stats.marks_evaluated;
        EXPECT_GT(gpu.stats.criteria_seconds, 0);
      }
    }
  }
}

// The tiles' diamond errors stay on the GPU: a view that does not change
// uploads only each quad's small tables again (grid steps, sides). Over the
// budget, the errors a frame did not use go at its end (a frame's own stay).
TEST(GlRefineCriteria, AStaticViewUploadsTheDiamondErrorsOnce) {
  criteria();  // the GL context
  const Case& a = case_named("scotland");
  const Case& b = case_named("down");  // the Pyrenees: other tiles
  for (const uint64_t budget : {uint64_t{256} << 20, uint64_t{1}}) {
    SCOPED_TRACE(budget);
    auto gl = GlRefineCriteria::create(budget);
    ASSERT_TRUE(gl) << gl.error().message;
    // Bytes uploaded to refine c's view.
    // own_cache: the diamond errors die with the call (their owners
    // expire: the GPU's copies are stale, and their addresses may be reused
    // by the next tile's errors).
    auto refine_view = [&](const Case& c, bool own_cache = false) -> uint64_t {
      Terrain& t = c.terrain();
      auto view = lod::make_view(c.camera);
      EXPECT_TRUE(view);
      const lod::Selection s = select(t, *view, c.pixel_error);
      lod::RefineOptions o;
      o.pixel_error = c.pixel_error;
      lod::RefineCache scratch(0);
      o.cache = own_cache ? &scratch : &t.cache;
      o.criteria = gl->get();
      const uint64_t before = (*gl)->bytes_uploaded();
      auto mesh = lod::refine(*view, t.terrain, s, o);
      EXPECT_TRUE(mesh) << mesh.error().message;
      EXPECT_EQ(mesh->indices,
                refined(t, *view, s, c.pixel_error, lod::RefineVariant::kTopDown).indices);
      return (*gl)->bytes_uploaded() - before;
    };
    const uint64_t first = refine_view(a), again = refine_view(a);
    const uint64_t resident = (*gl)->resident_bytes();
    EXPECT_GT(resident, first / 2);  // most of it: the errors
    EXPECT_LT(again * 10, first) << first << " then " << again;
    refine_view(b);
    if (budget > 1) {
      EXPECT_GT((*gl)->resident_bytes(), resident);  // both views'
      EXPECT_EQ(refine_view(a), again);
    } else {  // only the last frame's
      EXPECT_LT((*gl)->resident_bytes(), resident);
      // (The first frame also sized the classes' buffer.)
      EXPECT_GT(refine_view(a) * 10, first * 9);
    }
    // Errors measured anew each time, the last ones' expired: uploaded
    // again, and the expired ones dropped at the end of the next frame.
    const uint64_t kept = (*gl)->resident_bytes();
    for (int i = 0; i < 2; ++i) EXPECT_GT(refine_view(a, true) * 10, first * 9);
    refine_view(a);
    EXPECT_EQ((*gl)->resident_bytes(), kept);
  }
}

// Decides every diamond "over the threshold", whatever the shader says.
struct EverythingOver final : lod::CriterionEvaluator {
  Status evaluate(const lod::CriterionFrame& frame, std::span<const lod::CriterionQuad> quads,
                  std::vector<std::vector<uint8_t>>& classes) override {
    RELIEF_CHECK(criteria().evaluate(frame, quads, classes));
    for (auto& c : classes) std::fill(c.begin(), c.end(), uint8_t(lod::CriterionClass::kOver));
    return {};
  }
};

// The refinement decides by the evaluator's classes, with a history given
// too (as view::Scene refines: nothing is recorded then, since recording
// would evaluate every criterion again on the CPU), in lanes too.
TEST(GlRefineCriteria, TheRefinementDecidesByTheClassesWithAHistoryAndInLanes) {
  const Case& c = case_named("down");
  Terrain& t = c.terrain();
  auto view = lod::make_view(c.camera);
  ASSERT_TRUE(view);
  const lod::Selection s = select(t, *view, c.pixel_error);
  const lod::RefinedMesh cpu = refined(t, *view, s, c.pixel_error, lod::RefineVariant::kTopDown);
  lod::RefineHistory history;
  PooledExecutor lanes(2);
  EverythingOver over;
  for (Executor* executor : {static_cast<Executor*>(nullptr), static_cast<Executor*>(&lanes)}) {
    lod::RefineOptions o;
    o.pixel_error = c.pixel_error;
    o.cache = &t.cache;
    o.history = &history;
    o.executor = executor;
    o.criteria = &criteria();
    for (int frame = 0; frame < 2; ++frame) {
      auto gpu = lod::refine(*view, t.terrain, s, o);
      ASSERT_TRUE(gpu) << gpu.error().message;
      EXPECT_EQ(gpu->indices, cpu.indices);
    }
    o.criteria = &over;
    auto all = lod::refine(*view, t.terrain, s, o);
    ASSERT_TRUE(all) << all.error().message;
    EXPECT_GT(all->triangles(), 4 * cpu.triangles());
  }
}

TEST(GlRefineCriteria, AGridWithoutClassesIsAnError) {
  lod::View view;
  lod::CriterionFrame f;
  f.view = &view;
  std::vector<std::vector<uint8_t>> classes;
  const Status s = criteria().evaluate(f, {}, classes);
  ASSERT_FALSE(s);
  EXPECT_NE(s.error().message.find("classes of diamonds"), std::string::npos) << s.error().message;
}

}  // namespace
}  // namespace relief::render
