// Wavelet soft thresholding on synthetic speckle with a known mean, and on
// real SAR: the mean survives, the speckle shrinks.
#include <gtest/gtest.h>

#include <cmath>
#include <random>

#include "fixture.h"

namespace relief::process {
namespace {

using namespace relief::process::testing;

double mean_of(const Image& im) {
  double s = 0;
  for (float v : im.v) s += v;
  return s / static_cast<double>(im.v.size());
}

double cv_of(const Image& im) {  // coefficient of variation
  const double m = mean_of(im);
  double q = 0;
  for (float v : im.v) q += (v - m) * (v - m);
  return std::sqrt(q / static_cast<double>(im.v.size())) / m;
}

TEST(Wavelet, KeepsTheMeanAndReducesSpeckle) {
  for (double looks : {1.0, 4.0}) {
    // L-look amplitudes of a constant reflectivity: sqrt of Gamma(L, 1/L) intensity.
    std::mt19937 rng(7);
    std::gamma_distribution<double> intensity(looks, 1 / looks);
    Image in{200, 200, {}};
    for (int k = 0; k < 200 * 200; ++k)
      in.v.push_back(static_cast<float>(100 * std::sqrt(intensity(rng))));
    ThreadExecutor ex(2);
    const Image out = run("wavelet", {"levels=3", "k=1", "looks=" + std::to_string(looks)}, in, ex);
    SCOPED_TRACE(looks);
    EXPECT_NEAR(mean_of(out) / mean_of(in), 1.0, 0.03);
    EXPECT_LT(cv_of(out), cv_of(in) / 2);
  }
}

TEST(Wavelet, ThresholdZeroIsTheIdentityUpToTheBias) {
  // With k = 0 nothing is thresholded: c_J + sum w_j telescopes to ln a.
  const Image in = umbra_crop(1000, 1000, 80, 60);
  InlineExecutor ex;
  const Image out = run("wavelet", {"levels=2", "k=0", "looks=1"}, in, ex);
  const double bias = std::exp(std::lgamma(1.5) - 0.5 * (-0.5772156649));
  for (int y = 0; y < out.height; ++y) {
    for (int x = 0; x < out.width; ++x) {
      const float a = in.at(x + 6, y + 6);
      if (a <= 0) continue;
      ASSERT_NEAR(out.at(x, y), a * bias, 1e-4 * a);
    }
  }
}

TEST(Wavelet, QuadByQuadWithBordersEqualsWholeImageBitForBit) {
  const Image in = umbra_crop(300, 400, 200, 180);
  ThreadExecutor ex(2);
  for (int levels : {1, 3})
    expect_quads_equal_whole("wavelet", {"levels=" + std::to_string(levels)}, in, ex);
}

}  // namespace
}  // namespace relief::process
