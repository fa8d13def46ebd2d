// Dynamic-range reduction: every operator against a scalar reference written
// straight from its formula (seed 003 §2.2), on the real Umbra SAR image;
// monotonic global mappings; the SAR extensions' limits; quads equal the whole.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <functional>

#include "fixture.h"
#include "relief/process/dynamic_range.h"

namespace relief::process {
namespace {

using namespace relief::process::testing;

// Gauss average of radius r (sigma = r / 2.5) around (x, y), computed directly in 2-D.
double gauss_at(const Image& in, int x, int y, int r) {
  const double sigma = r / 2.5;
  double s = 0, w = 0;
  for (int dy = -r; dy <= r; ++dy) {
    for (int dx = -r; dx <= r; ++dx) {
      const double k =
          std::exp(-0.5 * dx * dx / (sigma * sigma)) * std::exp(-0.5 * dy * dy / (sigma * sigma));
      const double v = in.at(x + dx, y + dy);
      if (std::isnan(v)) continue;
      s += k * v;
      w += k;
    }
  }
  return s / w;
}

// Compares an operator with a reference f(a, x, y) in input coordinates over
// every output sample; a NaN reference skips a sample.
void expect_matches(const std::string& name, const std::vector<std::string>& params,
                    const Image& in, const std::function<double(const Image&, int, int)>& f,
                    double tolerance) {
  SCOPED_TRACE(name);
  ThreadExecutor ex(2);
  const Image out = run(name, params, in, ex);
  const int m = (in.width - out.width) / 2;
  double worst = 0;
  for (int y = 0; y < out.height; ++y) {
    for (int x = 0; x < out.width; ++x) {
      const double ref = std::clamp(f(in, x + m, y + m), 0.0, 1.0);
      worst = std::max(worst, std::abs(out.at(x, y) - ref));
    }
  }
  EXPECT_LE(worst, tolerance);
}

TEST(ToneMapping, GlobalOperatorsFollowTheirFormulas) {
  const Image in = umbra_crop(500, 500, 200, 150);
  const GlobalStats g = stats_of(in);
  auto norm = [&](const Image& im, int x, int y) { return std::max(0.0f, im.at(x, y)) / g.max; };
  // RAT: mean of a^0.7 estimated from mean and std (see estimated_power_mean).
  const double m07 = std::pow(g.mean, 0.7) - 0.105 * std::pow(g.mean, -1.3) * g.stddev * g.stddev;
  expect_matches(
      "rat", {}, in,
      [&](const Image& im, int x, int y) { return std::pow(im.at(x, y), 0.7) / (2.5 * m07); },
      1e-6);
  expect_matches(
      "drago", {"c=50", "m=2", "b=0.5"}, in,
      [&](const Image& im, int x, int y) {
        const double a = norm(im, x, y);
        return 2 / std::log(51.0) * std::log(1 + 50 * a) / std::log(2 + 8 * std::pow(a, 0.5));
      },
      1e-6);
  expect_matches(
      "tumblin", {"c=200", "ad=40", "aa=3"}, in,
      [&](const Image& im, int x, int y) {
        auto gamma = [](double l) {
          return l > 100 ? 2.655 : 1.855 + 0.4 * std::log10(l + 2.3e-5);
        };
        return 40.0 / 100 * std::pow(200 * norm(im, x, y) / 3, gamma(3) / gamma(40));
      },
      1e-6);
  expect_matches(
      "schlick", {"b=30"}, in,
      [&](const Image& im, int x, int y) {
        const double a = norm(im, x, y);
        return 30 * a / (29 * a + 1);
      },
      1e-6);
  expect_matches(
      "reinhard-devlin", {"b=1.5", "c=0.3"}, in,
      [&](const Image& im, int x, int y) {
        const double a = norm(im, x, y), avg = g.mean / g.max, lo = g.min / g.max;
        const double l = 0.7 * a + 0.3 * avg;
        const double m = 0.3 + 0.7 * std::pow((1 - avg) / (1 - lo), 1.4);
        return a / (a + std::pow(std::exp(-1.5) * l, m));
      },
      1e-6);
}

TEST(ToneMapping, PowerMeanEstimateIsCloseOnRealSar) {
  const Image in = umbra_crop(0, 0, 2000, 2000);
  double sum = 0, n = 0;
  for (float v : in.v) sum += std::pow(v, 0.7), n += 1;
  const double exact = sum / n, estimate = estimated_power_mean(stats_of(in), 0.7);
  EXPECT_NEAR(estimate / exact, 1.0, 0.05);
}

TEST(ToneMapping, LocalOperatorsFollowTheirFormulas) {
  const Image in = umbra_crop(900, 800, 90, 80);
  const GlobalStats g = stats_of(in);
  const double s = 1 / g.max;
  auto a_of = [&](const Image& im, int x, int y) { return std::max(0.0f, im.at(x, y)) * s; };
  auto averages = [&](const Image& im, int x, int y, int n) {
    std::vector<double> out;
    for (int r = 1; r <= n; ++r) out.push_back(gauss_at(im, x, y, r) * s);
    return out;
  };
  expect_matches(
      "chiu", {"c=3", "radius=6"}, in,
      [&](const Image& im, int x, int y) {
        return a_of(im, x, y) / (3 * gauss_at(im, x, y, 6) * s);
      },
      1e-5);
  // The SAR adaptation value: the largest G_r with |G_(r-1) - G_r| / G_(r-1) > t.
  auto sar_a = [&](const Image& im, int x, int y, double t) {
    const auto gr = averages(im, x, y, 10);
    double adapted = a_of(im, x, y);
    for (int r = 1; r < 10; ++r) {
      if (std::abs(gr[r - 1] - gr[r]) / gr[r - 1] > t) adapted = gr[r];
    }
    return adapted;
  };
  const double b = 40;
  expect_matches(
      "ext-schlick", {"b=40", "d=0.7", "t=0.15"}, in,
      [&](const Image& im, int x, int y) {
        const double a = a_of(im, x, y);
        const double ap = 0.3 * a + 0.7 * sar_a(im, x, y, 0.15);
        return b * a / ((b - 1) * ap + 1);
      },
      1e-5);
  expect_matches(
      "ext-reinhard-devlin", {"b=2", "c=0.2", "d=1", "t=0.1"}, in,
      [&](const Image& im, int x, int y) {
        const double a = a_of(im, x, y), avg = g.mean * s, lo = g.min * s;
        const double l = 0.8 * sar_a(im, x, y, 0.1) + 0.2 * avg;
        const double m = 0.3 + 0.7 * std::pow((1 - avg) / (1 - lo), 1.4);
        return a / (a + std::pow(std::exp(-2.0) * l, m));
      },
      1e-5);
  expect_matches(
      "retinex", {"p=80", "w=0.5", "range=1.5", "max_radius=10"}, in,
      [&](const Image& im, int x, int y) {
        const double a = a_of(im, x, y), w[] = {1, 0.5, 0.25};
        const int radii[] = {2, 5, 10};
        double sum = 0;
        for (int k = 0; k < 3; ++k) {
          sum +=
              w[k] * (std::log(1 + 80 * a) - std::log(1 + 80 * gauss_at(im, x, y, radii[k]) * s));
        }
        return 0.5 + sum / 1.75 / 3;
      },
      1e-5);
  auto capacity = [](double l) {
    if (l < 0.0034) return l / 0.0014;
    if (l < 1) return 2.4483 + std::log10(l / 0.0034) / 0.4027;
    if (l < 7.2444) return 16.5630 + (l - 1) / 0.4027;
    return 32.0693 + std::log10(l / 7.2444) / 0.0556;
  };
  expect_matches(
      "ashikhmin", {"c=100", "t=0.3"}, in,
      [&](const Image& im, int x, int y) {
        const auto gr = averages(im, x, y, 10);
        double adapted = gr[0];
        for (int r = 1; r < 10 && std::abs(gr[r - 1] - gr[r]) / gr[r - 1] < 0.3; ++r)
          adapted = gr[r];
        const double lo = capacity(100 * g.min * s), hi = capacity(100);
        return (capacity(100 * adapted) - lo) / (hi - lo) * a_of(im, x, y) / adapted;
      },
      1e-5);
  expect_matches(
      "reinhard", {"c=5", "w=3", "s=8", "t=0.05"}, in,
      [&](const Image& im, int x, int y) {
        const auto gr = averages(im, x, y, 10);
        double adapted = gr[0];
        for (int r = 1; r < 10; ++r) {
          const double v = 5 * (gr[r - 1] - gr[r]) / (256.0 * 5 / (r * r) + 5 * gr[r - 1]);
          if (std::abs(v) >= 0.05) break;
          adapted = gr[r];
        }
        const double l = 5 * a_of(im, x, y);
        return l * (1 + l / 9) / (1 + 5 * adapted);
      },
      1e-5);
  // Durand: the bilateral range weights are tabulated (4096 steps over 4
  // sigma_r), hence the looser tolerance.
  expect_matches(
      "durand", {"radius=4", "sigma_r=0.5", "k=0.3"}, in,
      [&](const Image& im, int x, int y) {
        auto lg = [&](int xx, int yy) { return std::log10(std::max(1e-6, a_of(im, xx, yy))); };
        const double c = lg(x, y), ss = 4 / 2.5;
        double sum = 0, wsum = 0;
        for (int dy = -4; dy <= 4; ++dy) {
          for (int dx = -4; dx <= 4; ++dx) {
            const double v = lg(x + dx, y + dy), d = v - c;
            if (std::abs(d) >= 2.0) continue;
            const double w =
                std::exp(-0.5 * (dx * dx + dy * dy) / (ss * ss)) * std::exp(-0.5 * d * d / 0.25);
            sum += w * v;
            wsum += w;
          }
        }
        const double base = sum / wsum;
        return std::pow(10.0, 0.3 * base + c - base);
      },
      2e-3);
}

TEST(ToneMapping, GlobalMappingsAreMonotonic) {
  Image ramp{1000, 1, {}};
  for (int i = 0; i < 1000; ++i) ramp.v.push_back(static_cast<float>(i * i) / 100);
  ThreadExecutor ex(2);
  for (const auto& op : operator_catalogue()) {
    if (!op.needs_global_stats) continue;
    if (margin_of(op, *parse_params(op, {})) > 0) continue;  // local operators
    const Image out = run(op.name, {}, ramp, ex);
    for (int i = 1; i < 1000; ++i) ASSERT_GE(out.v[i], out.v[i - 1]) << op.name << " at " << i;
    EXPECT_LT(out.v[0], out.v[999]) << op.name;
  }
}

TEST(ToneMapping, ExtendedMethodsWithoutAdaptivityAreTheGlobalOnes) {
  const Image in = umbra_crop(100, 1200, 120, 100);
  ThreadExecutor ex(2);
  const Image global = run("schlick", {"b=25"}, in, ex);
  const Image local = run("ext-schlick", {"b=25", "d=0"}, in, ex);
  const Image rd = run("reinhard-devlin", {"b=1", "c=0.5"}, in, ex);
  const Image ext_rd = run("ext-reinhard-devlin", {"b=1", "c=0.5", "d=0"}, in, ex);
  for (int y = 0; y < local.height; ++y) {
    for (int x = 0; x < local.width; ++x) {
      ASSERT_FLOAT_EQ(local.at(x, y), global.at(x + 10, y + 10));
      ASSERT_FLOAT_EQ(ext_rd.at(x, y), rd.at(x + 10, y + 10));
    }
  }
}

TEST(ToneMapping, SarAdaptationEmphasisesAPeak) {
  // A bright point on a homogeneous background: the adapted value at the peak
  // is a wide average, darker than the peak, so the peak maps brighter than
  // with the global method; far from the peak nothing changes.
  Image in{61, 61, std::vector<float>(61 * 61, 100.0f)};
  in.v[30 * 61 + 30] = 2000.0f;
  in.v[60 * 61 + 60] = 20000.0f;  // the maximum, elsewhere: the peak is not white already
  ThreadExecutor ex(2);
  const GlobalStats g = stats_of(in);
  const Image global = run("schlick", {"b=10"}, in, ex, &g);
  const Image local = run("ext-schlick", {"b=10", "d=1", "t=0.1"}, in, ex, &g);
  EXPECT_LT(global.at(30, 30), 0.6);
  EXPECT_GT(local.at(20, 20), global.at(30, 30) + 0.3);
  EXPECT_FLOAT_EQ(local.at(5, 5), global.at(15, 15));
}

TEST(ToneMapping, QuadByQuadWithBordersEqualsWholeImageBitForBit) {
  const Image in = umbra_crop(600, 300, 220, 200);
  ThreadExecutor ex(2);
  for (const auto& op : operator_catalogue()) {
    if (op.needs_global_stats || op.name == "wavelet" || op.params.empty()) {
      expect_quads_equal_whole(op.name, {}, in, ex);
    }
  }
}

TEST(Conversions, DecibelsAndIntensityRoundTrip) {
  const Image in = umbra_crop(50, 50, 40, 30);
  InlineExecutor ex;
  const Image db = run("amplitude-to-db", {}, in, ex);
  const Image back = run("db-to-amplitude", {}, db, ex);
  const Image intensity = run("amplitude-to-intensity", {}, in, ex);
  const Image amplitude = run("intensity-to-amplitude", {}, intensity, ex);
  for (size_t k = 0; k < in.v.size(); ++k) {
    if (in.v[k] <= 0) {
      EXPECT_TRUE(std::isnan(db.v[k]));  // no logarithm: nodata
      continue;
    }
    EXPECT_NEAR(db.v[k], 20 * std::log10(in.v[k]), 1e-4);
    EXPECT_NEAR(back.v[k], in.v[k], 1e-4 * in.v[k]);
    EXPECT_NEAR(amplitude.v[k], in.v[k], 1e-4 * in.v[k]);
  }
}

}  // namespace
}  // namespace relief::process
