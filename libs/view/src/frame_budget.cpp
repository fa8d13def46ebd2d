// The frame-time budget's factor: up at once by the overrun (capped), back
// down exponentially while frames fit or the view is still, snapping to
// exactly 1 at the end.
#include "relief/view/frame_budget.h"

#include <algorithm>
#include <cmath>

namespace relief::view {

namespace {
// A factor this close to 1 is 1: the threshold is the one given, bit for bit.
constexpr double kSnap = 0.01;

double towards_one(double factor, double dt, double seconds) {
  const double keep = seconds > 0 ? std::exp(-std::max(dt, 0.0) / seconds) : 0;
  return 1 + (factor - 1) * keep;
}
}  // namespace

double FrameBudget::update(double frame_ms, double dt, bool moving) {
  const FrameBudgetOptions& o = options_;
  if (o.target_ms <= 0) {
    factor_ = 1;
  } else if (!moving) {
    factor_ = towards_one(factor_, dt, o.settle_seconds);
  } else if (frame_ms > o.over * o.target_ms) {
    const double step = std::min(frame_ms / o.target_ms, std::max(o.max_step, 1.0));
    factor_ = std::min(factor_ * step, std::max(o.max_factor, 1.0));
  } else if (frame_ms > 0 && frame_ms < o.under * o.target_ms) {
    factor_ = towards_one(factor_, dt, o.recover_seconds);
  }
  if (factor_ - 1 < kSnap) factor_ = 1;
  return factor_;
}

}  // namespace relief::view
