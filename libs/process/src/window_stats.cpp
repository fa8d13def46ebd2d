#include "relief/process/window_stats.h"

#include <cmath>

namespace relief::process {

WindowStats window_stats(ConstView in, int radius) {
  WindowStats st;
  st.width = in.width - 2 * radius;
  st.height = in.height - 2 * radius;
  assert(st.width > 0 && st.height > 0);
  const size_t cols = static_cast<size_t>(in.width);
  // Pass 1: per output row, sums over the 2r+1 input rows of every column.
  std::vector<double> vs(cols), vq(cols), vc(cols);
  st.sum.resize(static_cast<size_t>(st.width) * static_cast<size_t>(st.height));
  st.sum_sq.resize(st.sum.size());
  st.count.resize(st.sum.size());
  for (int y = 0; y < st.height; ++y) {
    std::fill(vs.begin(), vs.end(), 0.0);
    std::fill(vq.begin(), vq.end(), 0.0);
    std::fill(vc.begin(), vc.end(), 0.0);
    for (int k = 0; k <= 2 * radius; ++k) {
      const float* row = in.row(y + k);
      for (size_t x = 0; x < cols; ++x) {
        const double v = row[x];
        const bool valid = !std::isnan(v);
        vs[x] += valid ? v : 0.0;
        vq[x] += valid ? v * v : 0.0;
        vc[x] += valid ? 1.0 : 0.0;
      }
    }
    // Pass 2: sums over 2r+1 columns.
    double* os = &st.sum[st.index(0, y)];
    double* oq = &st.sum_sq[st.index(0, y)];
    double* oc = &st.count[st.index(0, y)];
    for (int x = 0; x < st.width; ++x) {
      double s = 0, q = 0, c = 0;
      for (int k = 0; k <= 2 * radius; ++k) {
        s += vs[x + k];
        q += vq[x + k];
        c += vc[x + k];
      }
      os[x] = s;
      oq[x] = q;
      oc[x] = c;
    }
  }
  return st;
}

}  // namespace relief::process
