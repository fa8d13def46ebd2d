#include "relief/process/window_stats.h"

#include <cmath>

namespace relief::process {

namespace {

// Integers up to 2^20 keep every window sum of values and squares (at most
// 19 x 19 of them) below 2^53, where doubles are exact: running sums then give
// the same bits as direct sums in any order.
bool exact_integers(ConstView in) {
  constexpr float kLimit = 1 << 20;
  for (int y = 0; y < in.height; ++y) {
    const float* row = in.row(y);
    for (int x = 0; x < in.width; ++x) {
      const float v = row[x];
      if (std::isnan(v)) continue;
      if (v != std::floor(v) || std::abs(v) > kLimit) return false;
    }
  }
  return true;
}

inline void accumulate(float v, double sign, double& s, double& q, double& c) {
  if (std::isnan(v)) return;
  const double d = v;
  s += sign * d;
  q += sign * d * d;
  c += sign;
}

}  // namespace

WindowStats window_stats(ConstView in, int radius) {
  WindowStats st;
  st.width = in.width - 2 * radius;
  st.height = in.height - 2 * radius;
  assert(st.width > 0 && st.height > 0);
  const int len = 2 * radius + 1;
  const bool running = exact_integers(in);
  const size_t cols = static_cast<size_t>(in.width);
  std::vector<double> vs(cols, 0.0), vq(cols, 0.0), vc(cols, 0.0);
  st.sum.resize(static_cast<size_t>(st.width) * static_cast<size_t>(st.height));
  st.sum_sq.resize(st.sum.size());
  st.count.resize(st.sum.size());
  for (int y = 0; y < st.height; ++y) {
    // Pass 1: per column, the sums over input rows [y, y + 2r].
    if (running && y > 0) {
      const float* add = in.row(y + len - 1);
      const float* drop = in.row(y - 1);
      for (size_t x = 0; x < cols; ++x) {
        accumulate(add[x], 1.0, vs[x], vq[x], vc[x]);
        accumulate(drop[x], -1.0, vs[x], vq[x], vc[x]);
      }
    } else {
      std::fill(vs.begin(), vs.end(), 0.0);
      std::fill(vq.begin(), vq.end(), 0.0);
      std::fill(vc.begin(), vc.end(), 0.0);
      for (int k = 0; k < len; ++k) {
        const float* row = in.row(y + k);
        for (size_t x = 0; x < cols; ++x) accumulate(row[x], 1.0, vs[x], vq[x], vc[x]);
      }
    }
    // Pass 2: sums of those over columns [x, x + 2r].
    double* os = &st.sum[st.index(0, y)];
    double* oq = &st.sum_sq[st.index(0, y)];
    double* oc = &st.count[st.index(0, y)];
    double s = 0, q = 0, c = 0;
    for (int x = 0; x < st.width; ++x) {
      if (running && x > 0) {
        s += vs[x + len - 1] - vs[x - 1];
        q += vq[x + len - 1] - vq[x - 1];
        c += vc[x + len - 1] - vc[x - 1];
      } else {
        s = q = c = 0;
        for (int k = 0; k < len; ++k) {
          s += vs[x + k];
          q += vq[x + k];
          c += vc[x + k];
        }
      }
      os[x] = s;
      oq[x] = q;
      oc[x] = c;
    }
  }
  return st;
}

}  // namespace relief::process
