// Speed-dependent level of detail: the threshold's factor follows the view's
// speed up at once (a fast view stops asking for detail it would pass before
// it arrives) and comes back down exponentially when the view slows, snapping
// to exactly 1 at the end so the still frame is the complete one.
#include "relief/view/speed_lod.h"

#include <algorithm>
#include <cmath>

namespace relief::view {

namespace {
// A factor this close to 1 is 1: the threshold is the still one, bit for bit.
constexpr double kSpeedSnap = 0.01;
}  // namespace

double SpeedLod::threshold(double still_pixels, double dt, double angular_speed,
                           double linear_speed, double height_above_ground) {
  if (!options_.enabled) {
    factor_ = 1;
    return still_pixels;
  }
  // Linear speed in heights above the ground per second: what moves the
  // picture, 100 m/s is fast at 10 m and slow at 10 km.
  const double relative = std::abs(linear_speed) / std::max(height_above_ground, 1.0);
  const double target = std::clamp(
      1 + std::abs(angular_speed) / options_.angular_scale + relative / options_.linear_scale, 1.0,
      std::max(options_.max_factor, 1.0));
  if (target >= factor_) {
    factor_ = target;
  } else if (dt > 0) {
    const double keep = options_.settle_seconds > 0 ? std::exp(-dt / options_.settle_seconds) : 0;
    factor_ = target + (factor_ - target) * keep;
  }
  if (factor_ - 1 < kSpeedSnap) factor_ = 1;
  return factor_ == 1 ? still_pixels : still_pixels * factor_;
}

}  // namespace relief::view
