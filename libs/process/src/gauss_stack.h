#pragma once
// Gauss-filtered versions G_r of an image for several radii r (mask
// (2r+1)^2, sigma = r / 2.5 so the mask holds almost all of the filter's
// mass), the local averages behind the local tone-mapping operators. Nodata
// samples are left out and the weights renormalised. Sums run in a fixed order
// over a fixed neighbourhood, so quads with borders match the whole image.
#include <vector>

#include "relief/process/view.h"

namespace relief::process {

class GaussStack {
 public:
  // `in` extends max(radii) beyond the output on every side; radii >= 1.
  GaussStack(ConstView in, std::vector<int> radii);
  int margin() const { return margin_; }
  // Computes every G_r for output row y.
  void compute_row(int y);
  // G for the k-th radius given to the constructor: output-width values.
  const double* level(size_t k) const { return levels_[k].data(); }

 private:
  ConstView in_;
  std::vector<int> radii_;
  int margin_ = 0, width_ = 0;
  std::vector<std::vector<double>> kernels_, levels_;
  std::vector<double> column_sum_, column_weight_;
};

// Radii 1, 2, ..., n.
std::vector<int> radii_up_to(int n);

}  // namespace relief::process
