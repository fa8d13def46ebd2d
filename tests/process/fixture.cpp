#include "fixture.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstring>

#include "../ingest/gdal_reference.h"
#include "../support/test_support.h"

namespace relief::process::testing {

Image umbra_crop(int x0, int y0, int w, int h) {
  static const auto src =
      relief::testing::read_source(relief::testing::data("sar/umbra_mount_yasur.tif"));
  Image img{w, h, std::vector<float>(static_cast<size_t>(w) * h)};
  for (int y = 0; y < h; ++y) {
    for (int x = 0; x < w; ++x) img.v[y * w + x] = static_cast<float>(src.at(x0 + x, y0 + y));
  }
  return img;
}

GlobalStats stats_of(const Image& in) {
  GlobalStats g{INFINITY, -INFINITY, 0, 0};
  double n = 0, sum = 0, sq = 0;
  for (float v : in.v) {
    if (std::isnan(v)) continue;
    n += 1;
    sum += v;
    sq += double(v) * v;
    g.min = std::min<double>(g.min, v);
    g.max = std::max<double>(g.max, v);
  }
  g.mean = sum / n;
  g.stddev = std::sqrt(std::max(0.0, sq / n - g.mean * g.mean));
  return g;
}

Image run(const std::string& name, const std::vector<std::string>& params, const Image& in,
          Executor& ex, const GlobalStats* stats) {
  const OperatorSpec* op = find_operator(name);
  EXPECT_NE(op, nullptr) << name;
  auto p = parse_params(*op, params);
  EXPECT_TRUE(p) << p.error().message;
  const int m = margin_of(*op, *p);
  Image out{in.width - 2 * m, in.height - 2 * m, {}};
  out.v.resize(static_cast<size_t>(out.width) * out.height);
  const GlobalStats g = stats ? *stats : stats_of(in);
  auto st = run_operator(*op, *p, in.cview(), out.view(), ex, &g);
  EXPECT_TRUE(st) << st.error().message;
  return out;
}

void expect_quads_equal_whole(const std::string& name, const std::vector<std::string>& params,
                              const Image& in, Executor& ex) {
  SCOPED_TRACE(name);
  const GlobalStats g = stats_of(in);  // global operators: the dataset's, not the quad's
  const Image whole = run(name, params, in, ex, &g);
  const int m = (in.width - whole.width) / 2;
  constexpr int kQuadW = 64, kQuadH = 48;
  for (int qy = 0; qy < whole.height; qy += kQuadH) {
    for (int qx = 0; qx < whole.width; qx += kQuadW) {
      const int w = std::min(kQuadW, whole.width - qx), h = std::min(kQuadH, whole.height - qy);
      Image quad_in{w + 2 * m, h + 2 * m, {}};
      for (int y = 0; y < quad_in.height; ++y) {
        for (int x = 0; x < quad_in.width; ++x) quad_in.v.push_back(in.at(qx + x, qy + y));
      }
      const Image quad = run(name, params, quad_in, ex, &g);
      for (int y = 0; y < h; ++y) {
        ASSERT_EQ(
            std::memcmp(&quad.v[y * w], &whole.v[(qy + y) * whole.width + qx], w * sizeof(float)),
            0)
            << "quad at " << qx << "," << qy << " row " << y;
      }
    }
  }
}

}  // namespace relief::process::testing
