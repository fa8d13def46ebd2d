// The exact window sums of mean, Lee and Kuan (window_stats.h) against the
// old definition computed brute force: the window's mean and sum of squared
// deviations from its (2r+1)^2 samples in long double, on real SAR
// amplitudes (the raw integers and resampled floats, as a store holds them).
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <limits>

#include "fixture.h"
#include "relief/process/window_stats.h"

namespace relief::process {
namespace {

using namespace relief::process::testing;

// Resampled amplitudes as a store's tiles hold them: floats with full
// mantissas (the mean of 2 x 2 raw amplitudes, scaled), not integers.
Image resampled(const Image& in, float scale, float offset = 0) {
  Image out{in.width - 1, in.height - 1, {}};
  for (int y = 0; y < out.height; ++y) {
    for (int x = 0; x < out.width; ++x) {
      const float mean =
          (in.at(x, y) + in.at(x + 1, y) + in.at(x, y + 1) + in.at(x + 1, y + 1)) / 4.0f;
      out.v.push_back(mean * scale + offset);
    }
  }
  return out;
}

struct Brute {
  long double sum = 0, dev_sq = 0;
  int n = 0;
};

// The window of radius r whose top-left input sample is (x, y), two passes.
Brute brute(const Image& in, int x, int y, int r) {
  Brute b;
  for (int k = 0; k <= 2 * r; ++k) {
    for (int j = 0; j <= 2 * r; ++j) {
      const float v = in.at(x + j, y + k);
      if (!std::isnan(v)) b.sum += v, ++b.n;
    }
  }
  const long double mean = b.n ? b.sum / b.n : 0;
  for (int k = 0; k <= 2 * r; ++k) {
    for (int j = 0; j <= 2 * r; ++j) {
      const float v = in.at(x + j, y + k);
      if (!std::isnan(v)) b.dev_sq += (v - mean) * (v - mean);
    }
  }
  return b;
}

// Largest relative errors of the exact sums against the brute force.
struct Worst {
  double sum = 0, dev_sq = 0;
};

Worst compare_with_brute(const Image& in, int r, WindowSums::Mode mode) {
  WindowSums sums(in.cview(), r, all_small_integers(in.cview()), mode);
  Worst w;
  for (int y = 0; y + 2 * r < in.height; ++y) {
    sums.next_row(y);
    for (int x = 0; x < sums.width(); ++x) {
      const Brute b = brute(in, x, y, r);
      EXPECT_EQ(sums.count()[x], b.n);
      const double sum = static_cast<double>(b.sum), dev = static_cast<double>(b.dev_sq);
      w.sum = std::max(w.sum, std::abs(sums.sum()[x] - sum) / std::max(std::abs(sum), 1e-300));
      w.dev_sq = std::max(w.dev_sq, std::abs(sums.dev_sq()[x] - dev) / std::max(dev, 1e-300));
    }
  }
  return w;
}

TEST(WindowSums, ExactSumsEqualTheBruteForceOnRealSar) {
  const Image raw = umbra_crop(700, 900, 120, 90);
  const Image floats = resampled(raw, 0.37f);
  // Amplitudes on a large offset: mean of squares minus square of the mean
  // cancels there (Ci^2 ~ 1e-6), the exact path does not.
  const Image offset = resampled(raw, 0.37f, 1e5f);
  for (const Image* in : {&raw, &floats, &offset}) {
    for (int r : {1, 3, 8}) {
      SCOPED_TRACE("image " + std::to_string(in - &raw) + " r=" + std::to_string(r));
      const Worst exact = compare_with_brute(*in, r, WindowSums::Mode::exact);
      // The sum rounded once; the deviations: the exact integer rounded
      // once, divided by n once (and the brute force's own rounding).
      EXPECT_LE(exact.sum, 0x1p-52);
      EXPECT_LE(exact.dev_sq, 4e-16);
      const Worst old = compare_with_brute(*in, r, WindowSums::Mode::double_);
      char worst[32];
      std::snprintf(worst, sizeof worst, "%.3g", old.dev_sq);
      RecordProperty("old_dev_sq_" + std::to_string(in - &raw) + "_r" + std::to_string(r), worst);
      if (in == &offset) {
        EXPECT_GT(old.dev_sq, 1e-12) << "the double sums do cancel here";
      }
    }
  }
}

// Values whose magnitudes span more bits than the integer sums hold (1e-30
// beside amplitudes, an infinity) make their rows' windows decide one by
// one: those that fit stay exact, the others take the direct double sums;
// either way a quad equals the whole image bit for bit.
TEST(WindowSums, WideSpansDecideWindowByWindowAndTileSeamlessly) {
  Image in = resampled(umbra_crop(300, 400, 201, 161), 0.37f);
  in.v[static_cast<size_t>(40 * in.width + 50)] = 1e-30f;
  in.v[static_cast<size_t>(100 * in.width + 120)] = std::numeric_limits<float>::infinity();
  in.v[static_cast<size_t>(60 * in.width + 60)] = NAN;
  ThreadExecutor ex(2);
  for (const char* name : {"mean", "lee", "kuan"}) {
    expect_quads_equal_whole(name, {"radius=3"}, in, ex);
  }
  // Away from the infinity, the sums are exact or direct: within rounding.
  const int r = 3;
  WindowSums sums(in.cview(), r, false, WindowSums::Mode::exact);
  for (int y = 0; y + 2 * r < 80; ++y) {
    sums.next_row(y);
    for (int x = 0; x < sums.width(); ++x) {
      const Brute b = brute(in, x, y, r);
      ASSERT_NEAR(sums.sum()[x], static_cast<double>(b.sum), 1e-13 * static_cast<double>(b.sum));
      ASSERT_NEAR(sums.dev_sq()[x], static_cast<double>(b.dev_sq),
                  1e-9 * static_cast<double>(b.dev_sq) + 1e-9);
    }
  }
}

// Lee, Kuan and the mean from the exact sums equal the old definition (the
// window's mean and unbiased variance, brute force in long double, then the
// filter's formula) within one float ulp of their output, away from the
// thresholds where either side may take the other branch.
TEST(WindowSums, MeanLeeKuanEqualTheBruteForceWithinAFloatUlp) {
  const Image raw = umbra_crop(1200, 600, 110, 80);
  ThreadExecutor ex(2);
  for (const Image& in : {raw, resampled(raw, 0.37f)}) {
    for (const char* name : {"mean", "lee", "kuan"}) {
      for (int r : {1, 3}) {
        SCOPED_TRACE(std::string(name) + " r=" + std::to_string(r));
        std::vector<std::string> params = {"radius=" + std::to_string(r)};
        if (std::string(name) != "mean") params.push_back("looks=2");
        const Image out = run(name, params, in, ex);
        int compared = 0;
        for (int y = 0; y < out.height; ++y) {
          for (int x = 0; x < out.width; ++x) {
            const Brute b = brute(in, x, y, r);
            const long double m = b.sum / b.n, var = b.n > 1 ? b.dev_sq / (b.n - 1) : 0;
            const long double i = in.at(x + r, y + r), cu2 = 0.5L;
            long double expected = m;
            if (std::string(name) != "mean" && var > 1e-10L && m > 1e-10L) {
              const long double ci2 = var / (m * m);
              if (std::abs(ci2 - cu2) <= 1e-9L * cu2) continue;  // either branch
              if (ci2 >= cu2) {
                long double w = 1 - cu2 / ci2;
                if (std::string(name) == "kuan") w /= 1 + cu2;
                expected = i * w + m * (1 - w);
              }
            }
            const float e = static_cast<float>(expected), got = out.at(x, y);
            const float ulp = std::nextafter(e, INFINITY) - e;
            ASSERT_LE(std::abs(got - e), ulp) << x << "," << y << ": " << got << " vs " << e;
            ++compared;
          }
        }
        EXPECT_GT(compared, out.width * out.height * 9 / 10);
      }
    }
  }
}

}  // namespace
}  // namespace relief::process
