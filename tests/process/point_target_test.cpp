// Point-target detection on synthetic cross-shaped responses with known
// centres and side-lobe axes, PSLR of a sampled sinc, and quads = whole.
#include <gtest/gtest.h>

#include <cmath>
#include <numbers>
#include <random>

#include "fixture.h"
#include "relief/process/point_targets.h"

namespace relief::process {
namespace {

using namespace relief::process::testing;

double sinc(double x) {
  return x == 0 ? 1.0 : std::sin(std::numbers::pi * x) / (std::numbers::pi * x);
}

// Adds a point-target response: |sinc(u / s) sinc(v / s)| with u along
// `axis_deg` (counter-clockwise from +x, rows down) and v perpendicular.
void add_target(Image& img, int cx, int cy, double peak, double axis_deg, double s,
                double s_across = 0) {
  if (s_across == 0) s_across = s;
  const double a = axis_deg * std::numbers::pi / 180;
  for (int y = 0; y < img.height; ++y) {
    for (int x = 0; x < img.width; ++x) {
      const double dx = x - cx, dy = -(y - cy);
      const double u = dx * std::cos(a) + dy * std::sin(a),
                   v = -dx * std::sin(a) + dy * std::cos(a);
      img.v[y * img.width + x] +=
          static_cast<float>(peak * std::abs(sinc(u / s) * sinc(v / s_across)));
    }
  }
}

Image speckle(int w, int h, double mean, unsigned seed) {
  std::mt19937 rng(seed);
  std::exponential_distribution<double> intensity(1.0);
  Image img{w, h, {}};
  for (int k = 0; k < w * h; ++k) {
    img.v.push_back(static_cast<float>(mean * std::sqrt(intensity(rng)) / 0.8862));
  }
  return img;
}

std::vector<Detection> detect(const Image& img, const DetectorParams& p = {}) {
  double hi = 0;
  for (float v : img.v) hi = std::max<double>(hi, v);
  return detect_point_targets(img.cview(), hi, p);
}

TEST(PointTargets, CrossesAreFoundWithTheirAxes) {
  Image img = speckle(160, 120, 10, 3);
  add_target(img, 40, 50, 1000, 30, 1.2);
  add_target(img, 110, 70, 800, 0, 1.2);
  add_target(img, 80, 20, 900, 45, 1.2);
  const auto found = detect(img);
  ASSERT_EQ(found.size(), 3u);
  auto axes = [](const Detection& d) {
    return std::pair{std::min(d.direction[0], d.direction[1]),
                     std::max(d.direction[0], d.direction[1])};
  };
  // Raster order: (80, 20), (40, 50), (110, 70).
  EXPECT_EQ(found[0].x, 80);
  EXPECT_EQ(found[0].y, 20);
  EXPECT_EQ(axes(found[0]), std::pair(45.0, 135.0));
  EXPECT_EQ(found[1].x, 40);
  EXPECT_EQ(found[1].y, 50);
  EXPECT_EQ(axes(found[1]), std::pair(30.0, 120.0));
  EXPECT_EQ(found[2].x, 110);
  EXPECT_EQ(found[2].y, 70);
  EXPECT_EQ(axes(found[2]), std::pair(0.0, 90.0));
  for (const auto& d : found) {
    EXPECT_LT(d.pslr_db, 0);
    EXPECT_GT(d.pslr_db, -30);
  }
}

TEST(PointTargets, SensitivityAndLevelFilter) {
  Image img = speckle(120, 120, 10, 5);
  add_target(img, 60, 60, 1000, 0, 1.2);
  add_target(img, 30, 30, 120, 0, 1.2);  // 12 % of the maximum: below the 15 % floor
  EXPECT_EQ(detect(img).size(), 1u);
  EXPECT_EQ(detect(img, {0.05, 1.5}).size(), 2u);
  EXPECT_TRUE(detect(img, {0.15, 50}).empty());  // a very high t finds nothing
  // Speckle alone has no cross-shaped responses.
  EXPECT_TRUE(detect(speckle(200, 200, 10, 9)).empty());
}

TEST(PointTargets, AnalysisMeasuresTheSincPslrAndWidth) {
  // An oversampled sinc (4 and 3 samples per resolution cell): PSLR -13.26 dB
  // (the sampled lobe peaks are -13.47 and -13.7 dB), -3 dB widths 0.886 * 4
  // = 3.54 and 0.886 * 3 = 2.66 samples.
  Image img{129, 129, std::vector<float>(129 * 129, 0.0f)};
  add_target(img, 64, 64, 1000, 0, 4, 3);
  Detection d;
  d.x = 64, d.y = 64, d.amplitude = 1000, d.direction[0] = 0, d.direction[1] = 90;
  const TargetAnalysis t = analyse_point_target(img.cview(), d, 40);
  const double widths[] = {3.54, 2.66};
  for (int k = 0; k < 2; ++k) {
    const CrossSection& axis = t.axes[k];
    EXPECT_NEAR(axis.pslr_db, -13.26, 0.6);
    EXPECT_NEAR(axis.width_3db, widths[k], 0.25);
    ASSERT_EQ(axis.db.size(), 81u);
    EXPECT_DOUBLE_EQ(axis.db[40], 0.0);
  }
  const auto plot = plot_cross_sections(t, 320, 200);
  ASSERT_EQ(plot.size(), 320u * 200 * 4);
  size_t red = 0, blue = 0;
  for (size_t p = 0; p < plot.size(); p += 4) {
    red += plot[p] == 200 && plot[p + 1] == 40;
    blue += plot[p + 2] == 200 && plot[p] == 40;
  }
  EXPECT_GT(red, 100u);
  EXPECT_GT(blue, 100u);
}

TEST(PointTargets, QuadByQuadEqualsWholeImage) {
  const Image img = umbra_crop(0, 300, 600, 400);
  double hi = 0;
  for (float v : img.v) hi = std::max<double>(hi, v);
  const DetectorParams p{0.15, 1.5};
  const auto whole = detect_point_targets(img.cview(), hi, p);
  ASSERT_GT(whole.size(), 5u);
  std::vector<Detection> quads;
  const int m = kDetectorMargin;
  for (int qy = 0; qy < img.height - 2 * m; qy += 70) {
    for (int qx = 0; qx < img.width - 2 * m; qx += 90) {
      const int w = std::min(90, img.width - 2 * m - qx), h = std::min(70, img.height - 2 * m - qy);
      const ConstView v = img.cview().window(qx, qy, w + 2 * m, h + 2 * m);
      for (const auto& d : detect_point_targets(v, hi, p)) quads.push_back(d);
    }
  }
  auto key = [](const Detection& d) { return std::pair{d.y, d.x}; };
  std::sort(quads.begin(), quads.end(), [&](auto& a, auto& b) { return key(a) < key(b); });
  ASSERT_EQ(quads.size(), whole.size());
  for (size_t k = 0; k < whole.size(); ++k) {
    EXPECT_EQ(key(quads[k]), key(whole[k]));
    EXPECT_EQ(quads[k].direction[0], whole[k].direction[0]);
    EXPECT_EQ(quads[k].pslr_db, whole[k].pslr_db);
  }
}

}  // namespace
}  // namespace relief::process
