#include "relief/pipeline/fuse_tiles.h"

#include <algorithm>
#include <cmath>

#include <fmt/format.h>

namespace relief::pipeline {

Result<std::vector<double>> fuse_weights(std::vector<double> weights, size_t inputs,
                                         const std::string& inputs_name) {
  if (weights.empty()) weights.assign(inputs, 1.0);
  if (weights.size() != inputs) {
    return fail(
        fmt::format("--weights: {} weights for {} {}", weights.size(), inputs, inputs_name));
  }
  for (double w : weights) {
    if (!(w > 0) || !std::isfinite(w)) {
      return fail(fmt::format("--weights: {} is not > 0 and finite", w));
    }
  }
  const double largest = *std::max_element(weights.begin(), weights.end());
  for (double& w : weights) w /= largest;
  return weights;
}

void fuse_float(const std::vector<const tiles::Raster*>& in, const std::vector<double>& weights,
                FuseMode mode, tiles::Raster& out) {
  auto dst = out.f32();
  for (size_t s = 0; s < dst.size(); ++s) {
    double sum = 0, wsum = 0;
    for (size_t i = 0; i < in.size(); ++i) {
      if (!in[i]) continue;
      const float v = in[i]->f32()[s];
      if (std::isnan(v)) continue;
      sum += weights[i] * v;
      wsum += weights[i];
      if (mode == FuseMode::First) break;
    }
    dst[s] = wsum > 0 ? static_cast<float>(sum / wsum) : NAN;
  }
}

tiles::Raster upsample(const tiles::Raster& ancestor, const geo::TileKey& a,
                       const geo::TileKey& target, const geo::TileGrid& grid) {
  const int w = grid.width(), h = grid.height(), b = grid.border();
  const double f = std::ldexp(1.0, target.level - a.level);
  tiles::Raster out =
      tiles::Raster::empty(ancestor.type(), grid.padded_width(), grid.padded_height());
  const bool rgba = ancestor.type() == tiles::SampleType::UInt8;
  const int aw = ancestor.width(), ah = ancestor.height();
  // Ancestor bordered coordinate of a target sample centre (global sample units).
  auto position = [&](int64_t target_origin, int index, int64_t ancestor_origin) {
    const double global = (static_cast<double>(target_origin + index) + 0.5) / f - 0.5;
    return global - static_cast<double>(ancestor_origin) + b;
  };
  for (int bj = 0; bj < out.height(); ++bj) {
    const double v = position(int64_t{target.y} * h, bj - b, int64_t{a.y} * h);
    const int y0 = std::clamp(static_cast<int>(std::floor(v)), 0, ah - 2);
    const double fy = std::clamp(v - y0, 0.0, 1.0);
    for (int bi = 0; bi < out.width(); ++bi) {
      const double u = position(int64_t{target.x} * w, bi - b, int64_t{a.x} * w);
      const int x0 = std::clamp(static_cast<int>(std::floor(u)), 0, aw - 2);
      const double fx = std::clamp(u - x0, 0.0, 1.0);
      const int nearest_x = x0 + (fx >= 0.5), nearest_y = y0 + (fy >= 0.5);
      if (!ancestor.valid(nearest_x, nearest_y)) continue;
      const size_t o = static_cast<size_t>(bj) * out.width() + bi;
      double sum[4] = {0, 0, 0, 0}, wsum = 0;
      for (int k = 0; k < 4; ++k) {
        const int x = x0 + k % 2, y = y0 + k / 2;
        if (!ancestor.valid(x, y)) continue;
        const double wgt = (k % 2 ? fx : 1 - fx) * (k / 2 ? fy : 1 - fy);
        const size_t s = static_cast<size_t>(y) * aw + x;
        if (rgba) {
          for (int c = 0; c < 4; ++c) sum[c] += wgt * ancestor.u8()[s * 4 + c];
        } else {
          sum[0] += wgt * ancestor.f32()[s];
        }
        wsum += wgt;
      }
      if (wsum <= 0) continue;
      if (rgba) {
        for (int c = 0; c < 4; ++c) {
          out.u8()[o * 4 + c] =
              static_cast<uint8_t>(std::clamp(std::lround(sum[c] / wsum), 0L, 255L));
        }
        out.u8()[o * 4 + 3] = std::max<uint8_t>(out.u8()[o * 4 + 3], 1);
      } else {
        out.f32()[o] = static_cast<float>(sum[0] / wsum);
      }
    }
  }
  return out;
}

}  // namespace relief::pipeline
