#include "gauss_stack.h"

#include <algorithm>
#include <cassert>
#include <cmath>

namespace relief::process {

std::vector<int> radii_up_to(int n) {
  std::vector<int> r;
  for (int k = 1; k <= n; ++k) r.push_back(k);
  return r;
}

GaussStack::GaussStack(ConstView in, std::vector<int> radii) : in_(in), radii_(std::move(radii)) {
  for (int r : radii_) {
    assert(r >= 1);
    margin_ = std::max(margin_, r);
    const double sigma = r / 2.5;
    std::vector<double> k(static_cast<size_t>(2 * r + 1));
    for (int d = -r; d <= r; ++d) k[d + r] = std::exp(-0.5 * d * d / (sigma * sigma));
    kernels_.push_back(std::move(k));
  }
  width_ = in.width - 2 * margin_;
  levels_.assign(radii_.size(), std::vector<double>(static_cast<size_t>(std::max(0, width_))));
  column_sum_.resize(static_cast<size_t>(in.width));
  column_weight_.resize(column_sum_.size());
}

void GaussStack::compute_row(int y) {
  const int cy = y + margin_;  // the output row's centre row in the input
  for (size_t k = 0; k < radii_.size(); ++k) {
    const int r = radii_[k];
    const std::vector<double>& kernel = kernels_[k];
    // Vertical pass over the columns this radius reaches.
    const int x0 = margin_ - r, x1 = margin_ + width_ + r;
    std::fill(column_sum_.begin() + x0, column_sum_.begin() + x1, 0.0);
    std::fill(column_weight_.begin() + x0, column_weight_.begin() + x1, 0.0);
    for (int d = -r; d <= r; ++d) {
      const float* row = in_.row(cy + d);
      const double w = kernel[d + r];
      for (int x = x0; x < x1; ++x) {
        if (std::isnan(row[x])) continue;
        column_sum_[x] += w * row[x];
        column_weight_[x] += w;
      }
    }
    // Horizontal pass.
    double* out = levels_[k].data();
    for (int x = 0; x < width_; ++x) {
      double s = 0, wsum = 0;
      const int c = x + margin_;
      for (int d = -r; d <= r; ++d) {
        s += kernel[d + r] * column_sum_[c + d];
        wsum += kernel[d + r] * column_weight_[c + d];
      }
      out[x] = wsum > 0 ? s / wsum : NAN;
    }
  }
}

}  // namespace relief::process
