#include "relief/process/point_targets.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <numbers>

namespace relief::process {
namespace {

constexpr int kDirections = 12;
constexpr double kStepDegrees = 15;

// Bilinear sample at (x + ox, y + oy) of the view: integer centre plus an
// offset, split so the weights depend on the offset alone (the same in every
// quad); NaN outside or where a corner is nodata.
double bilinear(ConstView in, int x, int y, double ox, double oy) {
  const double fox = std::floor(ox), foy = std::floor(oy);
  const int x0 = x + static_cast<int>(fox), y0 = y + static_cast<int>(foy);
  if (x0 < 0 || y0 < 0 || x0 >= in.width || y0 >= in.height) return NAN;
  const double fx = ox - fox, fy = oy - foy;
  const int x1 = fx > 0 ? x0 + 1 : x0, y1 = fy > 0 ? y0 + 1 : y0;
  if (x1 >= in.width || y1 >= in.height) return NAN;
  const double a = in.at(x0, y0), b = in.at(x1, y0), c = in.at(x0, y1), d = in.at(x1, y1);
  return (a * (1 - fx) + b * fx) * (1 - fy) + (c * (1 - fx) + d * fx) * fy;
}

struct Offsets {
  double dx[kDirections], dy[kDirections];
};

const Offsets& unit_offsets() {
  static const Offsets o = [] {
    Offsets r;
    for (int k = 0; k < kDirections; ++k) {
      const double a = k * kStepDegrees * std::numbers::pi / 180;
      r.dx[k] = std::cos(a);
      r.dy[k] = -std::sin(a);  // rows point down
    }
    return r;
  }();
  return o;
}

double angle_between(double a, double b) {
  const double d = std::abs(a - b);
  return std::min(d, 180 - d);
}

bool is_local_maximum(ConstView in, int cx, int cy, float centre) {
  for (int dy = -kDetectorMargin; dy <= kDetectorMargin; ++dy) {
    for (int dx = -kDetectorMargin; dx <= kDetectorMargin; ++dx) {
      if (!dx && !dy) continue;
      const float v = in.at(cx + dx, cy + dy);
      if (std::isnan(v)) continue;
      const bool earlier = dy < 0 || (dy == 0 && dx < 0);
      if (earlier ? v >= centre : v > centre) return false;
    }
  }
  return true;
}

}  // namespace

std::vector<Detection> detect_point_targets(ConstView in, double max_amplitude,
                                            const DetectorParams& p) {
  std::vector<Detection> found;
  const int m = kDetectorMargin;
  const double floor_amplitude = p.level * max_amplitude;
  const Offsets& u = unit_offsets();
  for (int y = m; y < in.height - m; ++y) {
    for (int x = m; x < in.width - m; ++x) {
      const float a = in.at(x, y);
      if (!(a >= floor_amplitude) || !(a > 0)) continue;
      if (!is_local_maximum(in, x, y, a)) continue;
      double window_sum = 0;
      int window_n = 0;
      for (int dy = -m; dy <= m; ++dy) {
        for (int dx = -m; dx <= m; ++dx) {
          const float v = in.at(x + dx, y + dy);
          if (!std::isnan(v)) window_sum += v, ++window_n;
        }
      }
      const double window_mean = window_sum / window_n;
      std::array<double, kDirections> mean;
      for (int k = 0; k < kDirections; ++k) {
        double s = 0;
        int n = 0;
        for (int r = 1; r <= m; ++r) {
          for (int side : {-1, 1}) {
            const double v = bilinear(in, x, y, side * r * u.dx[k], side * r * u.dy[k]);
            if (!std::isnan(v)) s += v, ++n;
          }
        }
        mean[k] = n ? s / n : 0;
      }
      // The strongest direction, then the strongest at least 45 degrees from it.
      const int first = static_cast<int>(std::max_element(mean.begin(), mean.end()) - mean.begin());
      int second = -1;
      for (int k = 0; k < kDirections; ++k) {
        if (angle_between(k * kStepDegrees, first * kStepDegrees) < 45) continue;
        if (second < 0 || mean[k] > mean[second]) second = k;
      }
      const double need = p.sensitivity * window_mean;
      if (mean[first] < need || mean[second] < need) continue;
      // Rough PSLR: the brightest cross-section sample 2-3 samples out.
      double lobe = 0;
      for (int k : {first, second}) {
        for (int r = 2; r <= m; ++r) {
          for (int side : {-1, 1}) {
            const double v = bilinear(in, x, y, side * r * u.dx[k], side * r * u.dy[k]);
            if (!std::isnan(v)) lobe = std::max(lobe, v);
          }
        }
      }
      Detection d;
      d.x = in.origin_x + x;
      d.y = in.origin_y + y;
      d.amplitude = a;
      d.direction[0] = first * kStepDegrees;
      d.direction[1] = second * kStepDegrees;
      d.pslr_db = lobe > 0 ? 20 * std::log10(lobe / a) : -INFINITY;
      found.push_back(d);
    }
  }
  return found;
}

namespace {

CrossSection cross_section(ConstView in, int cx, int cy, double peak, double direction, int half) {
  CrossSection c;
  c.direction = direction;
  const double a = direction * std::numbers::pi / 180, ux = std::cos(a), uy = -std::sin(a);
  std::vector<double> amp;
  for (int r = -half; r <= half; ++r) amp.push_back(bilinear(in, cx, cy, r * ux, r * uy));
  for (double v : amp) c.db.push_back(v > 0 ? 20 * std::log10(v / peak) : NAN);
  // Walk out from the peak to the first null (the first sample not lower than
  // the next) on each side; the highest sample beyond is the peak side lobe.
  double lobe = 0;
  for (int side : {-1, 1}) {
    int r = 1;
    while (r < half && !std::isnan(amp[half + side * (r + 1)]) &&
           amp[half + side * (r + 1)] < amp[half + side * r]) {
      ++r;
    }
    for (int k = r + 1; k <= half; ++k) {
      const double v = amp[half + side * k];
      if (!std::isnan(v)) lobe = std::max(lobe, v);
    }
  }
  c.pslr_db = lobe > 0 ? 20 * std::log10(lobe / peak) : -INFINITY;
  // -3 dB width: where the amplitude crosses peak / sqrt(2) on either side.
  const double half_power = peak / std::sqrt(2.0);
  double width = 0;
  for (int side : {-1, 1}) {
    for (int k = 1; k <= half; ++k) {
      const double inner = amp[half + side * (k - 1)], outer = amp[half + side * k];
      if (std::isnan(outer)) break;
      if (outer <= half_power) {
        width += (k - 1) + (inner - half_power) / (inner - outer);
        break;
      }
    }
  }
  c.width_3db = width;
  return c;
}

}  // namespace

TargetAnalysis analyse_point_target(ConstView in, const Detection& d, int half_length) {
  TargetAnalysis t;
  t.x = d.x;
  t.y = d.y;
  t.amplitude = d.amplitude;
  t.half_length = half_length;
  const int cx = static_cast<int>(d.x - in.origin_x), cy = static_cast<int>(d.y - in.origin_y);
  for (int k = 0; k < 2; ++k) {
    t.axes[k] = cross_section(in, cx, cy, d.amplitude, d.direction[k], half_length);
  }
  t.pslr_db = std::max(t.axes[0].pslr_db, t.axes[1].pslr_db);
  return t;
}

std::vector<uint8_t> plot_cross_sections(const TargetAnalysis& t, int width, int height) {
  std::vector<uint8_t> px(static_cast<size_t>(width) * height * 4, 255);
  auto put = [&](int x, int y, std::array<uint8_t, 3> c) {
    if (x < 0 || y < 0 || x >= width || y >= height) return;
    uint8_t* p = &px[(static_cast<size_t>(y) * width + x) * 4];
    p[0] = c[0], p[1] = c[1], p[2] = c[2], p[3] = 255;
  };
  constexpr double kFloorDb = -50;
  const int margin = 20;
  const int plot_w = width - 2 * margin, plot_h = height - 2 * margin;
  auto to_x = [&](double offset) {
    return margin +
           static_cast<int>(std::lround((offset + t.half_length) / (2.0 * t.half_length) * plot_w));
  };
  auto to_y = [&](double db) {
    return margin +
           static_cast<int>(std::lround(std::clamp(db, kFloorDb, 0.0) / kFloorDb * plot_h));
  };
  // Grid: every 10 dB, the centre line, and the PSLR level dashed.
  for (double db = 0; db >= kFloorDb; db -= 10) {
    for (int x = margin; x <= margin + plot_w; ++x) put(x, to_y(db), {210, 210, 210});
  }
  for (int y = margin; y <= margin + plot_h; ++y) put(to_x(0), y, {210, 210, 210});
  for (int x = margin; x <= margin + plot_w; x += 6) {
    for (int k = 0; k < 3; ++k) put(x + k, to_y(t.pslr_db), {120, 120, 120});
  }
  const std::array<uint8_t, 3> colours[2] = {{200, 40, 40}, {40, 80, 200}};
  for (int a = 0; a < 2; ++a) {
    const auto& db = t.axes[a].db;
    for (size_t k = 0; k + 1 < db.size(); ++k) {
      if (std::isnan(db[k]) || std::isnan(db[k + 1])) continue;
      // A line segment, drawn by stepping along its longer extent.
      const int x0 = to_x(static_cast<double>(k) - t.half_length),
                x1 = to_x(static_cast<double>(k) + 1 - t.half_length);
      const int y0 = to_y(db[k]), y1 = to_y(db[k + 1]);
      const int steps = std::max({std::abs(x1 - x0), std::abs(y1 - y0), 1});
      for (int s = 0; s <= steps; ++s) {
        const int x = x0 + (x1 - x0) * s / steps, y = y0 + (y1 - y0) * s / steps;
        put(x, y, colours[a]);
        put(x, y + 1, colours[a]);
      }
    }
  }
  return px;
}

}  // namespace relief::process
