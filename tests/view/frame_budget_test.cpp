// The frame budget: frames over it relax the threshold while the view
// moves, by their overrun but at most max_step per frame and max_factor in
// all; frames well within it bring it back, and below the speed's
// relaxation down to the floor it is given, never further; a still view
// returns to exactly the threshold given; no budget, no relaxation.
#include <gtest/gtest.h>

#include <cmath>

#include "relief/view/frame_budget.h"

namespace relief::view {
namespace {

constexpr double kDt = 1.0 / 30;

FrameBudgetOptions thirty_fps() {
  FrameBudgetOptions o;
  o.target_ms = 1000.0 / 30;
  return o;
}

TEST(FrameBudget, FramesOverTheBudgetRelaxByTheirOverrunCappedPerFrameAndInAll) {
  FrameBudget budget(thirty_fps());            // x1.3 per frame at most, x3 in all
  EXPECT_EQ(budget.update(0, kDt, true), 1);   // the first frame: nothing measured
  EXPECT_EQ(budget.update(35, kDt, true), 1);  // within over (1.1 x the budget)
  EXPECT_NEAR(budget.update(40, kDt, true), 1.2, 1e-12);
  EXPECT_NEAR(budget.update(100, kDt, true), 1.2 * 1.3, 1e-12);  // capped step
  for (int i = 0; i < 20; ++i) budget.update(1000, kDt, true);
  EXPECT_EQ(budget.factor(), 3);
  // In the band between under and over: held where the frames fit.
  EXPECT_EQ(budget.update(30, kDt, true), 3);
  EXPECT_EQ(budget.update(36, kDt, true), 3);
}

TEST(FrameBudget, FastFramesBringItBackSlowlyAStillViewQuicklyAndExactly) {
  FrameBudget budget(thirty_fps());
  for (int i = 0; i < 20; ++i) budget.update(1000, kDt, true);
  ASSERT_EQ(budget.factor(), 3);
  // Fast frames while moving: 1 s time constant.
  const double after_one_second = [&] {
    double f = 0;
    for (int i = 0; i < 30; ++i) f = budget.update(10, kDt, true);
    return f;
  }();
  EXPECT_NEAR(after_one_second, 1 + 2 * std::exp(-1.0), 1e-9);
  // Still, whatever the frames cost: 0.3 s, then exactly 1.
  double previous = after_one_second;
  int frames = 0;
  for (; frames < 300 && budget.update(500, kDt, false) != 1; ++frames) {
    ASSERT_LT(budget.factor(), previous);
    previous = budget.factor();
  }
  EXPECT_LT(frames, 60);
  EXPECT_EQ(budget.factor(), 1);
  EXPECT_EQ(budget.update(500, kDt, false), 1);
}

TEST(FrameBudget, FastFramesTightenTheSpeedsRelaxationDownToTheFloorNeverBelow) {
  FrameBudget budget(thirty_fps());
  // The speed relaxes the threshold 4 times: the floor is a quarter.
  constexpr double kFloor = 0.25;
  double previous = 1;
  for (int i = 0; i < 30; ++i) {
    const double f = budget.update(10, kDt, true, kFloor);
    ASSERT_LT(f, previous);
    ASSERT_GE(f, kFloor);
    previous = f;
  }
  // One second of fast frames: 1 s time constant towards the floor.
  EXPECT_NEAR(previous, kFloor + (1 - kFloor) * std::exp(-1.0), 1e-9);
  for (int i = 0; i < 600; ++i) budget.update(10, kDt, true, kFloor);
  EXPECT_NEAR(budget.factor(), kFloor, 1e-9);
  // The speed's relaxation falls to 2: the floor rises to a half at once.
  EXPECT_EQ(budget.update(10, kDt, true, 0.5), 0.5);
  // Frames in the band hold it; a slow one relaxes it from there.
  EXPECT_EQ(budget.update(30, kDt, true, 0.5), 0.5);
  EXPECT_NEAR(budget.update(40, kDt, true, 0.5), 0.5 * 1.2, 1e-12);
  // A still view: exactly 1 at once from below (the still threshold).
  EXPECT_EQ(budget.update(10, kDt, false, 0.5), 1);
}

TEST(FrameBudget, NoBudgetNeverRelaxes) {
  FrameBudget budget;  // the default: none
  for (int i = 0; i < 10; ++i) EXPECT_EQ(budget.update(1000, kDt, true), 1);
}

}  // namespace
}  // namespace relief::view
