// Top-down refinement in lanes (RefineOptions::executor): the mesh of one
// refiner whatever the number of lanes and whatever order or overlap the
// executor runs them in, with and without a history of decisions. Also run
// under ThreadSanitizer (the tsan preset selects this binary).
#include <gtest/gtest.h>

#include <algorithm>
#include <vector>

#include "refine_fixtures.h"
#include "relief/base/parallel.h"

namespace relief::lod {
namespace {

using namespace relief::lod::testing;

// Runs the lanes one after another on the calling thread, last first: every
// split sent across waits for a later round, the order furthest from the
// threads'. `lanes` is what it claims to run at once.
class BackwardsExecutor final : public Executor {
 public:
  explicit BackwardsExecutor(unsigned lanes) : lanes_(lanes) {}
  void parallel_for(size_t count, const std::function<void(size_t)>& body) override {
    ++calls;
    for (size_t i = count; i-- > 0;) body(i);
  }
  unsigned concurrency() const override { return lanes_; }
  int calls = 0;

 private:
  unsigned lanes_;
};

void expect_same_mesh(const RefinedMesh& a, const RefinedMesh& b) {
  EXPECT_EQ(a.indices, b.indices);
  ASSERT_EQ(a.quads.size(), b.quads.size());
  for (size_t i = 0; i < a.quads.size(); ++i) {
    EXPECT_EQ(a.quads[i].first_index, b.quads[i].first_index);
    EXPECT_EQ(a.quads[i].index_count, b.quads[i].index_count);
  }
  EXPECT_EQ(a.stats.unresolved, b.stats.unresolved);
  EXPECT_EQ(a.stats.max_unresolved_pixels, b.stats.max_unresolved_pixels);
  std::vector<geo::TileKey> x = a.stats.split_wanted, y = b.stats.split_wanted;
  std::sort(x.begin(), x.end());
  std::sort(y.begin(), y.end());
  EXPECT_EQ(x, y);
}

RefinedMesh refined_by(Terrain& t, const View& view, const Selection& s, double pixel_error,
                       Executor& executor) {
  RefineOptions o;
  o.pixel_error = pixel_error;
  o.cache = &t.cache;
  o.executor = &executor;
  auto mesh = refine(view, t.terrain, s, o);
  EXPECT_TRUE(mesh) << mesh.error().message;
  return mesh ? std::move(*mesh) : RefinedMesh{};
}

TEST(RefineLanes, AnyNumberOfLanesGivesTheMeshOfOneRefiner) {
  PooledExecutor two(2), five(5);
  BackwardsExecutor backwards(3);
  uint64_t unresolved = 0;
  for (const Case& c : cases()) {
    SCOPED_TRACE(c.name);
    Terrain& t = c.terrain();
    auto view = make_view(c.camera);
    ASSERT_TRUE(view);
    for (double pixel_error : {c.pixel_error, 3 * c.pixel_error}) {
      // A quad deeper than the level error allows leaves sides stuck: the
      // unresolved diamonds counted once across lanes.
      const Selection s = select(t, *view, pixel_error, c.name == std::string("low") ? 2.0 : 0.5);
      ASSERT_GT(s.quads.size(), 8u);
      const RefinedMesh one = refined(t, *view, s, pixel_error, RefineVariant::kTopDown);
      EXPECT_GT(one.triangles(), 8 * s.quads.size());
      unresolved += one.stats.unresolved;
      for (Executor* e : std::initializer_list<Executor*>{&two, &five, &backwards}) {
        SCOPED_TRACE(e->concurrency());
        const RefinedMesh lanes = refined_by(t, *view, s, pixel_error, *e);
        expect_same_mesh(lanes, one);
        // About the same criteria evaluated: in another order a forced split
        // may come before a diamond's own decision or after it, and a shared
        // side's diamond may be evaluated by both lanes.
        EXPECT_GT(lanes.stats.marks_evaluated, one.stats.marks_evaluated * 9 / 10);
        EXPECT_LT(lanes.stats.marks_evaluated, one.stats.marks_evaluated * 11 / 10);
      }
    }
  }
  EXPECT_GT(unresolved, 0u);  // the counts compared above were not all 0
  // Splits crossed between lanes: run backwards, some waited for a later round.
  EXPECT_GT(backwards.calls, 2 * static_cast<int>(cases().size()));
}

TEST(RefineLanes, ReusedDecisionsInLanesGiveTheMeshOfAFreshRefinement) {
  Terrain& t = pyrenees();
  PooledExecutor two(2);
  RefineHistory history;
  uint64_t reused = 0;
  for (int i = 0; i < 12; ++i) {
    SCOPED_TRACE(i);
    // Forward slowly, then turn: blocks reused, recorded by their lanes.
    const double range = 30000 - 20.0 * std::min(i, 6), heading = 20 + 0.05 * std::max(0, i - 6);
    auto view = make_view(look_at(1.45, 42.55, 1500, range, heading, -35, 60, 640, 480));
    ASSERT_TRUE(view);
    const Selection s = select(t, *view, 1.0);
    RefineOptions o;
    o.cache = &t.cache;
    o.history = &history;
    o.executor = &two;
    auto with = refine(*view, t.terrain, s, o);
    ASSERT_TRUE(with) << with.error().message;
    expect_same_mesh(*with, refined(t, *view, s, 1.0, RefineVariant::kTopDown));
    reused += with->stats.marks_reused;
  }
  EXPECT_GT(reused, 0u);
}

TEST(RefineLanes, BottomUpStaysOnTheCallingThread) {
  Terrain& t = pyrenees();
  const Case& c = case_named("down");
  auto view = make_view(c.camera);
  ASSERT_TRUE(view);
  const Selection s = select(t, *view, 4.0);
  BackwardsExecutor lanes(4);
  RefineOptions o;
  o.pixel_error = 4.0;
  o.cache = &t.cache;
  o.variant = RefineVariant::kBottomUp;
  o.executor = &lanes;
  auto m = refine(*view, t.terrain, s, o);
  ASSERT_TRUE(m) << m.error().message;
  EXPECT_EQ(lanes.calls, 0);
  expect_same_mesh(*m, refined(t, *view, s, 4.0, RefineVariant::kTopDown));
}

}  // namespace
}  // namespace relief::lod
