// The frame-time budget's factor: up at once by the overrun (capped), down
// exponentially towards the floor while frames are well within the budget
// and towards 1 while the view is still, snapping to exactly 1 when it
// comes back to it from above.
#include "relief/view/frame_budget.h"

#include <algorithm>
#include <cmath>

namespace relief::view {

namespace {
// A factor this close to 1 is 1: the threshold is the one given, bit for bit.
constexpr double kBudgetSnap = 0.01;

double towards(double target, double factor, double dt, double seconds) {
  const double keep = seconds > 0 ? std::exp(-std::max(dt, 0.0) / seconds) : 0;
  return target + (factor - target) * keep;
}
}  // namespace

double FrameBudget::update(double frame_ms, double dt, bool moving, double floor) {
  const FrameBudgetOptions& o = options_;
  floor = std::clamp(floor, kBudgetSnap, 1.0);  // a factor of 0 would be no threshold at all
  if (o.target_ms <= 0) {
    factor_ = 1;
  } else if (!moving) {
    factor_ = towards(1, factor_, dt, o.settle_seconds);
  } else if (frame_ms > o.over * o.target_ms) {
    const double step = std::min(frame_ms / o.target_ms, std::max(o.max_step, 1.0));
    factor_ = std::min(factor_ * step, std::max(o.max_factor, 1.0));
  } else if (frame_ms > 0 && frame_ms < o.under * o.target_ms) {
    factor_ = towards(floor, factor_, dt, o.recover_seconds);
  }
  // Never finer than the still threshold, whatever the floor was before.
  factor_ = std::max(factor_, moving ? floor : 1.0);
  // Snapped from above only: a factor tightening below 1 moves by less than
  // kBudgetSnap a frame when frames come often and must not be caught at 1.
  if (factor_ > 1 && factor_ - 1 < kBudgetSnap) factor_ = 1;
  return factor_;
}

}  // namespace relief::view
