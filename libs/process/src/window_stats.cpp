#include "relief/process/window_stats.h"

#include <algorithm>
#include <cmath>
#include <cstdint>

namespace relief::process {
namespace {}  // namespace

bool all_small_integers(ConstView in) {
  constexpr float kLimit = 1 << 20;
  for (int y = 0; y < in.height; ++y) {
    const float* row = in.row(y);
    // Branch-free over a row so the compiler can vectorise it: a value passes
    // when it is NaN, or small and equal to its integer truncation.
    bool ok = true;
    for (int x = 0; x < in.width; ++x) {
      const float v = row[x];
      const bool small = std::abs(v) <= kLimit;  // false for NaN
      const float t = small ? v : 0.0f;
      ok &= (small & (static_cast<float>(static_cast<int32_t>(t)) == t)) | (v != v);
    }
    if (!ok) return false;
  }
  return true;
}

namespace {

inline void accumulate(float v, double sign, double& s, double& q, double& c) {
  if (std::isnan(v)) return;
  const double d = v;
  s += sign * d;
  q += sign * d * d;
  c += sign;
}

}  // namespace

WindowSums::WindowSums(ConstView in, int radius, bool integral)
    : in_(in),
      radius_(radius),
      width_(in.width - 2 * radius),
      running_(integral),
      vs_(static_cast<size_t>(in.width)),
      vq_(vs_.size()),
      vc_(vs_.size()),
      sum_(static_cast<size_t>(std::max(0, width_))),
      sum_sq_(sum_.size()),
      count_(sum_.size()) {
  assert(width_ > 0 && in.height > 2 * radius);
}

void WindowSums::next_row(int y) {
  assert(y > last_row_ && y + 2 * radius_ < in_.height);
  const int len = 2 * radius_ + 1;
  const size_t cols = vs_.size();
  if (running_ && last_row_ >= 0 && y == last_row_ + 1) {
    const float* add = in_.row(y + len - 1);
    const float* drop = in_.row(y - 1);
    for (size_t x = 0; x < cols; ++x) {
      accumulate(add[x], 1.0, vs_[x], vq_[x], vc_[x]);
      accumulate(drop[x], -1.0, vs_[x], vq_[x], vc_[x]);
    }
  } else {
    std::fill(vs_.begin(), vs_.end(), 0.0);
    std::fill(vq_.begin(), vq_.end(), 0.0);
    std::fill(vc_.begin(), vc_.end(), 0.0);
    for (int k = 0; k < len; ++k) {
      const float* row = in_.row(y + k);
      for (size_t x = 0; x < cols; ++x) accumulate(row[x], 1.0, vs_[x], vq_[x], vc_[x]);
    }
  }
  last_row_ = y;
  double s = 0, q = 0, c = 0;
  for (int x = 0; x < width_; ++x) {
    if (running_ && x > 0) {
      s += vs_[x + len - 1] - vs_[x - 1];
      q += vq_[x + len - 1] - vq_[x - 1];
      c += vc_[x + len - 1] - vc_[x - 1];
    } else {
      s = q = c = 0;
      for (int k = 0; k < len; ++k) {
        s += vs_[x + k];
        q += vq_[x + k];
        c += vc_[x + k];
      }
    }
    sum_[x] = s;
    sum_sq_[x] = q;
    count_[x] = c;
  }
}

}  // namespace relief::process
