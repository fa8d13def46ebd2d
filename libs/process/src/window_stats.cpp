#include "relief/process/window_stats.h"

#include <algorithm>
#include <bit>
#include <cmath>
#include <cstdint>

namespace relief::process {

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

using u128 = unsigned __int128;

inline void accumulate(float v, double sign, double& s, double& q, double& c) {
  if (std::isnan(v)) return;
  const double d = v;
  s += sign * d;
  q += sign * d * d;
  c += sign;
}

// The exact path's bound: values are integers of at most kMaxBits bits, so a
// window's sum (at most 19 x 19 < 2^9 samples) stays below 2^62 and n sum(x^2)
// and sum(x)^2 below 2^124.
constexpr int kMaxBits = 53;

// The magnitudes' bit patterns of the nonzero valid values: the smallest and
// the largest (an infinity included; 0 and 0x7fffffff when there are none).
struct Magnitudes {
  uint32_t low = 0x7fffffffu, high = 0;
  void add(float v) {
    const uint32_t b = std::bit_cast<uint32_t>(v) & 0x7fffffffu;
    const bool valid = b <= 0x7f800000u;  // not NaN
    low = std::min(low, (valid && b != 0) ? b : 0x7fffffffu);
    high = std::max(high, valid ? b : 0u);
  }
  // Branch-free over a row, so that it vectorises.
  void add_row(const float* row, int n) {
    uint32_t lo = low, hi = high;
    for (int x = 0; x < n; ++x) {
      const uint32_t b = std::bit_cast<uint32_t>(row[x]) & 0x7fffffffu;
      const bool valid = b <= 0x7f800000u;
      lo = std::min(lo, (valid && b != 0) ? b : 0x7fffffffu);
      hi = std::max(hi, valid ? b : 0u);
    }
    low = lo, high = hi;
  }
  // The power of two whose integer multiples every value is (2^exp), or
  // false when the values span more than kMaxBits bits from there.
  bool scale(int& exp) const {
    if (high == 0) {  // zeros and nodata only
      exp = 0;
      return true;
    }
    // Biased exponents; subnormals are multiples of 2^-149 like exponent 1's.
    const int e_low = std::max<int>(static_cast<int>(low >> 23), 1),
              e_high = static_cast<int>(high >> 23);
    exp = e_low - 150;  // 2^(e - 127) has its last mantissa bit at 2^(e - 150)
    return e_high - e_low + 24 <= kMaxBits && e_high < 255;
  }
};

// 2^e as a double (|e| < 1023).
inline double pow2(int e) {
  return std::bit_cast<double>(static_cast<uint64_t>(1023 + e) << 52);
}

// A non-negative 128-bit integer rounded once to the nearest double (the
// shifted-out bits kept as a sticky bit, below the rounding position).
inline double to_double(u128 v) {
  const auto high = static_cast<uint64_t>(v >> 64);
  if (high == 0) return static_cast<double>(static_cast<uint64_t>(v));
  const int shift = 64 - std::countl_zero(high);
  auto top = static_cast<uint64_t>(v >> shift);
  if (static_cast<uint64_t>(v) << (64 - shift)) top |= 1;
  return static_cast<double>(top) * pow2(shift);
}

// The integer of `v` at scale 2^-exp (exact: `v` is a multiple of 2^exp);
// 0 for nodata.
inline int64_t fixed(float v, double inverse_scale) {
  return std::isnan(v) ? 0 : static_cast<int64_t>(static_cast<double>(v) * inverse_scale);
}

// A window's statistics from its exact integer sums at scale 2^exp.
inline void finish_exact(int64_t s, u128 q, int32_t c, int exp, double& sum, double& dev_sq,
                         double& count) {
  count = c;
  sum = static_cast<double>(s) * pow2(exp);
  if (c == 0) {
    dev_sq = 0;
    return;
  }
  // n sum(x^2) - sum(x)^2 >= 0 (Cauchy-Schwarz), exact; over n, the sum of
  // squared deviations.
  const u128 magnitude = static_cast<u128>(s < 0 ? -static_cast<__int128>(s) : s);
  const u128 d = static_cast<u128>(c) * q - magnitude * magnitude;
  dev_sq = to_double(d) / c * pow2(2 * exp);
}

}  // namespace

WindowSums::WindowSums(ConstView in, int radius, bool integral, Mode mode)
    : in_(in),
      radius_(radius),
      width_(in.width - 2 * radius),
      running_(integral),
      exact_(mode == Mode::exact),
      sum_(static_cast<size_t>(std::max(0, width_))),
      dev_sq_(sum_.size()),
      count_(sum_.size()) {
  assert(width_ > 0 && in.height > 2 * radius);
  const auto cols = static_cast<size_t>(in.width);
  if (!exact_) {
    vs_.resize(cols), vq_.resize(cols), vc_.resize(cols);
    return;
  }
  Magnitudes m;
  for (int y = 0; y < in.height; ++y) m.add_row(in.row(y), in.width);
  exact_running_ = m.scale(scale_exp_);
  if (exact_running_) xs_.resize(cols), xq_.resize(cols), xc_.resize(cols);
}

void WindowSums::next_row(int y) {
  assert(y > last_row_ && y + 2 * radius_ < in_.height);
  if (!exact_) {
    next_row_double(y);
  } else if (exact_running_) {
    next_row_exact(y);
  } else {
    for (int x = 0; x < width_; ++x) window_alone(x, y);
  }
  last_row_ = y;
}

void WindowSums::next_row_exact(int y) {
  const int len = 2 * radius_ + 1;
  const size_t cols = xs_.size();
  const double inverse = pow2(-scale_exp_);
  // Column sums, running down the rows (exact: the order cannot matter):
  // the entering row added and the leaving one taken out in one pass.
  if (last_row_ >= 0 && y == last_row_ + 1) {
    const float* add = in_.row(y + len - 1);
    const float* drop = in_.row(y - 1);
    for (size_t x = 0; x < cols; ++x) {
      const int64_t a = fixed(add[x], inverse), d = fixed(drop[x], inverse);
      xs_[x] += a - d;
      xq_[x] += static_cast<u128>(static_cast<__int128>(a) * a) -
                static_cast<u128>(static_cast<__int128>(d) * d);
      xc_[x] +=
          static_cast<int32_t>(!std::isnan(add[x])) - static_cast<int32_t>(!std::isnan(drop[x]));
    }
  } else {
    std::fill(xs_.begin(), xs_.end(), 0);
    std::fill(xq_.begin(), xq_.end(), 0);
    std::fill(xc_.begin(), xc_.end(), 0);
    for (int k = 0; k < len; ++k) {
      const float* row = in_.row(y + k);
      for (size_t x = 0; x < cols; ++x) {
        const int64_t v = fixed(row[x], inverse);
        xs_[x] += v;
        xq_[x] += static_cast<u128>(static_cast<__int128>(v) * v);
        xc_[x] += static_cast<int32_t>(!std::isnan(row[x]));
      }
    }
  }
  // Window sums, running along the row.
  int64_t s = 0;
  u128 q = 0;
  int32_t c = 0;
  for (int k = 0; k < len; ++k) s += xs_[k], q += xq_[k], c += xc_[k];
  for (int x = 0;; ++x) {
    finish_exact(s, q, c, scale_exp_, sum_[x], dev_sq_[x], count_[x]);
    if (x + 1 == width_) break;
    s += xs_[x + len] - xs_[x];
    q += xq_[x + len] - xq_[x];
    c += xc_[x + len] - xc_[x];
  }
}

// One window from its own values: exact when they fit, else the direct
// double sums (each column top to bottom, then the columns left to right).
void WindowSums::window_alone(int x, int y) {
  const int len = 2 * radius_ + 1;
  Magnitudes m;
  for (int k = 0; k < len; ++k) {
    for (int j = 0; j < len; ++j) m.add(in_.row(y + k)[x + j]);
  }
  int exp = 0;
  if (m.scale(exp)) {
    const double inverse = pow2(-exp);
    int64_t s = 0;
    u128 q = 0;
    int32_t c = 0;
    for (int k = 0; k < len; ++k) {
      for (int j = 0; j < len; ++j) {
        const float v = in_.row(y + k)[x + j];
        const int64_t f = fixed(v, inverse);
        s += f, q += static_cast<u128>(static_cast<__int128>(f) * f), c += !std::isnan(v);
      }
    }
    finish_exact(s, q, c, exp, sum_[x], dev_sq_[x], count_[x]);
    return;
  }
  double s = 0, q = 0, c = 0;
  for (int j = 0; j < len; ++j) {
    double vs = 0, vq = 0, vc = 0;
    for (int k = 0; k < len; ++k) accumulate(in_.row(y + k)[x + j], 1.0, vs, vq, vc);
    s += vs, q += vq, c += vc;
  }
  sum_[x] = s, count_[x] = c;
  dev_sq_[x] = c > 0 ? q - s * (s / c) : 0.0;
}

void WindowSums::next_row_double(int y) {
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
    // As the filters computed it before: q - s * mean.
    dev_sq_[x] = c > 0 ? q - s * (s / c) : 0.0;
    count_[x] = c;
  }
}

}  // namespace relief::process
