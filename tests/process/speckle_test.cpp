// Speckle filters: known answers, an independent scalar reference written from
// the formulas, quad-by-quad equals whole image bit for bit, and bad parameters.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstring>
#include <random>

#include "fixture.h"

namespace relief::process {
namespace {

using namespace relief::process::testing;

// --- an independent scalar reference, straight from the formulas -----------

double reference(const std::string& name, const Image& in, int x, int y, int r, double looks,
                 double deramp) {
  std::vector<double> win;
  for (int dy = -r; dy <= r; ++dy) {
    for (int dx = -r; dx <= r; ++dx) win.push_back(in.v[(y + dy) * in.width + x + dx]);
  }
  const double n = static_cast<double>(win.size());
  double mean = 0;
  for (double v : win) mean += v;
  mean /= n;
  double var = 0;
  for (double v : win) var += (v - mean) * (v - mean);
  var /= n - 1;
  const double i = in.v[y * in.width + x];
  if (name == "mean") return mean;
  if (std::abs(mean) < 1e-10) return 0;
  if (std::abs(var) < 1e-10) return mean;
  const double ci2 = var / (mean * mean), cu2 = 1 / looks;
  // Integer amplitudes can put Ci^2 exactly on a threshold, where rounding in
  // either implementation picks a branch: such samples are not comparable.
  auto near = [](double a, double b) { return std::abs(a - b) <= 1e-9 * std::abs(b); };
  if (name != "frost" && (near(ci2, cu2) || near(ci2, 2 * cu2))) return NAN;
  if (name == "frost") {
    const double alpha = deramp * var / (mean * mean);
    double norm = 0, acc = 0;
    for (int dy = -r; dy <= r; ++dy) {
      for (int dx = -r; dx <= r; ++dx) {
        const double c = std::exp(-alpha * std::sqrt(dx * dx + dy * dy));
        norm += c;
        acc += c * in.v[(y + dy) * in.width + x + dx];
      }
    }
    return acc / norm;
  }
  if (ci2 < cu2) return mean;
  if (name == "lee") return i * (1 - cu2 / ci2) + mean * (cu2 / ci2);
  if (name == "kuan") {
    const double w = (1 - cu2 / ci2) / (1 + cu2);
    return i * w + mean * (1 - w);
  }
  // gamma-map
  if (std::sqrt(ci2) >= std::sqrt(2 * cu2)) return i;
  const double alpha = (1 + cu2) / (ci2 - cu2), b = alpha - looks - 1;
  return (b * mean + std::sqrt(mean * mean * b * b + 4 * alpha * looks * mean * i)) / (2 * alpha);
}

TEST(Speckle, MatchesScalarReferenceOnRealSar) {
  const Image in = umbra_crop(700, 900, 160, 120);
  ThreadExecutor ex(2);
  for (const char* name : {"mean", "lee", "kuan", "gamma-map", "frost"}) {
    for (int r : {1, 2, 5}) {
      SCOPED_TRACE(std::string(name) + " r=" + std::to_string(r));
      std::vector<std::string> params = {"radius=" + std::to_string(r)};
      const double looks = std::string(name) == "frost" || std::string(name) == "mean" ? 1 : 2;
      if (looks != 1) params.push_back("looks=2");
      const Image out = run(name, params, in, ex);
      double worst = 0;
      for (int y = 0; y < out.height; ++y) {
        for (int x = 0; x < out.width; ++x) {
          const double ref = reference(name, in, x + r, y + r, r, looks, 0.1);
          if (std::isnan(ref)) continue;
          const double got = out.v[y * out.width + x];
          worst = std::max(worst, std::abs(got - ref) / std::max(1.0, std::abs(ref)));
        }
      }
      EXPECT_LE(worst, 1e-5);
    }
  }
}

TEST(Speckle, GaussAndMedianMatchScalarReferences) {
  const Image in = umbra_crop(1200, 600, 90, 70);
  ThreadExecutor ex(2);
  for (int r : {1, 3, 6}) {
    SCOPED_TRACE(r);
    const std::string radius = "radius=" + std::to_string(r);
    const Image gauss = run("gauss", {radius}, in, ex);
    const Image median = run("median", {radius}, in, ex);
    const double sigma = r / 2.5;
    for (int y = 0; y < gauss.height; ++y) {
      for (int x = 0; x < gauss.width; ++x) {
        double s = 0, w = 0;
        std::vector<float> window;
        for (int dy = -r; dy <= r; ++dy) {
          for (int dx = -r; dx <= r; ++dx) {
            const double k = std::exp(-0.5 * (dx * dx + dy * dy) / (sigma * sigma));
            const float v = in.at(x + r + dx, y + r + dy);
            s += k * v;
            w += k;
            window.push_back(v);
          }
        }
        ASSERT_NEAR(gauss.at(x, y), s / w, 1e-4 * std::max(1.0, s / w));
        if (r <= 3) {  // exact median; above, the documented separable approximation
          std::nth_element(window.begin(), window.begin() + window.size() / 2, window.end());
          ASSERT_EQ(median.at(x, y), window[window.size() / 2]);
        }
      }
    }
  }
}

TEST(Speckle, ConstantImageIsReturnedUnchanged) {
  Image in{40, 30, std::vector<float>(1200, 42.5f)};
  InlineExecutor ex;
  for (const char* name : {"mean", "gauss", "median", "lee", "kuan", "frost", "gamma-map"}) {
    const Image out = run(name, {"radius=3"}, in, ex);
    for (float v : out.v) ASSERT_FLOAT_EQ(v, 42.5f) << name;
  }
}

TEST(Speckle, QuadByQuadWithBordersEqualsWholeImageBitForBit) {
  // Integer amplitudes take the running-sum path; scaled ones the direct sums.
  Image integral = umbra_crop(300, 400, 300, 260);
  Image scaled = integral;
  for (float& v : scaled.v) v *= 0.37f;
  ThreadExecutor ex(2);
  for (const Image* image : {&integral, &scaled}) {
    for (const char* name : {"mean", "gauss", "median", "lee", "kuan", "frost", "gamma-map"}) {
      for (int r : {2, 5}) {
        SCOPED_TRACE("r=" + std::to_string(r));
        expect_quads_equal_whole(name, {"radius=" + std::to_string(r)}, *image, ex);
      }
    }
  }
}

TEST(Speckle, NodataIsLeftOutAndKept) {
  Image in{9, 9, std::vector<float>(81, 10.0f)};
  in.v[4 * 9 + 4] = NAN;  // centre
  in.v[4 * 9 + 5] = 1000.0f;
  in.v[3 * 9 + 3] = NAN;
  InlineExecutor ex;
  const Image mean = run("mean", {"radius=1"}, in, ex);  // 7 x 7 output
  EXPECT_TRUE(std::isnan(mean.v[3 * 7 + 3]));            // NaN centre stays NaN
  // Output (3, 2) is input (4, 3): its window holds both NaNs, left out.
  EXPECT_FLOAT_EQ(mean.v[2 * 7 + 3], (6 * 10.0f + 1000.0f) / 7);
  for (float v : run("median", {"radius=1"}, in, ex).v) {
    if (!std::isnan(v)) {
      EXPECT_EQ(v, 10.0f);
    }
  }
}

TEST(Speckle, BadParametersAreErrors) {
  const OperatorSpec* lee = find_operator("lee");
  ASSERT_NE(lee, nullptr);
  EXPECT_EQ(find_operator("sharpen"), nullptr);
  auto expect_error = [&](std::vector<std::string> p, const std::string& needle) {
    auto r = parse_params(*lee, p);
    ASSERT_FALSE(r);
    EXPECT_NE(r.error().message.find(needle), std::string::npos) << r.error().message;
  };
  expect_error({"radius=0"}, "out of range");
  expect_error({"radius=10"}, "out of range");
  expect_error({"radius=2.5"}, "whole number");
  expect_error({"looks=abc"}, "not a number");
  expect_error({"deramp=1"}, "no parameter 'deramp'");
  expect_error({"radius"}, "key=value");
  auto ok = parse_params(*lee, {"radius=4", "looks=3"});
  ASSERT_TRUE(ok);
  EXPECT_EQ(ok->at("radius"), 4);
  EXPECT_EQ(margin_of(*lee, *ok), 4);
}

TEST(DynamicRange, GlobalOperatorsFollowTheirFormulas) {
  const Image in = umbra_crop(500, 500, 200, 150);
  ThreadExecutor ex(2);
  double n = 0, sum = 0, sq = 0, lo = INFINITY, hi = -INFINITY;
  for (float v : in.v) {
    n += 1, sum += v, sq += double(v) * v, lo = std::min<double>(lo, v),
                                           hi = std::max<double>(hi, v);
  }
  const double mean = sum / n, sd = std::sqrt(sq / n - mean * mean);
  const Image lin = run("linear", {}, in, ex);
  const Image log = run("log", {"c=50"}, in, ex);
  const Image gam = run("gamma", {"gamma=0.7"}, in, ex);
  for (size_t k = 0; k < in.v.size(); ++k) {
    const double a = in.v[k];
    ASSERT_NEAR(lin.v[k], std::clamp(a / (mean + 3 * sd), 0.0, 1.0), 1e-6);
    const double x = std::clamp((a - lo) / (mean + 3 * sd - lo), 0.0, 1.0);
    ASSERT_NEAR(log.v[k], std::log1p(50 * x) / std::log1p(50), 1e-6);
    ASSERT_NEAR(gam.v[k], std::pow(a / hi, 0.7), 1e-6);
  }
}

TEST(DynamicRange, GlobalOperatorsAreMonotonicAndNeedStatistics) {
  Image ramp{256, 1, {}};
  for (int i = 0; i < 256; ++i) ramp.v.push_back(static_cast<float>(i));
  ThreadExecutor ex(2);
  for (const char* name : {"linear", "log", "gamma"}) {
    const Image out = run(name, {}, ramp, ex);
    for (int i = 1; i < 256; ++i) ASSERT_GE(out.v[i], out.v[i - 1]) << name << " at " << i;
    EXPECT_EQ(out.v[0], 0.0f) << name;
    // The ramp's mean + 3 std (349) lies above its maximum: only gamma, which
    // divides by the maximum, reaches white.
    if (std::string(name) == "gamma") {
      EXPECT_EQ(out.v[255], 1.0f);
    } else {
      EXPECT_LT(out.v[255], 1.0f) << name;
      EXPECT_GT(out.v[255], 0.7f) << name;
    }
    const OperatorSpec* op = find_operator(name);
    MutView o{const_cast<float*>(out.v.data()), 256, 1, 256, 0, 0};
    auto st = run_operator(*op, *parse_params(*op, {}), ramp.cview(), o, ex, nullptr);
    EXPECT_FALSE(st) << name;
  }
  Image flat{8, 8, std::vector<float>(64, 3.0f)};
  const OperatorSpec* lin = find_operator("linear");
  GlobalStats g{3, 3, 3, 0};
  Image out{8, 8, std::vector<float>(64)};
  auto st = run_operator(*lin, *parse_params(*lin, {}), flat.cview(), out.view(), ex, &g);
  ASSERT_FALSE(st);
  EXPECT_NE(st.error().message.find("no dynamic range"), std::string::npos);
}

}  // namespace
}  // namespace relief::process
