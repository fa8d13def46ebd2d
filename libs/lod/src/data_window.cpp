#include "relief/lod/data_window.h"

#include <algorithm>
#include <cmath>

namespace relief::lod {

float bilinear_height(const tiles::Raster& r, int border, double x, double y) {
  const double tx = x - 0.5 + border, ty = y - 0.5 + border;
  const double fx0 = std::floor(tx), fy0 = std::floor(ty);
  const float fx = static_cast<float>(tx - fx0), fy = static_cast<float>(ty - fy0);
  const int w = r.width(), h = r.height();
  const int x0 = std::clamp(static_cast<int>(fx0), 0, w - 1), x1 = std::min(x0 + 1, w - 1);
  const int y0 = std::clamp(static_cast<int>(fy0), 0, h - 1), y1 = std::min(y0 + 1, h - 1);
  const auto v = r.f32();
  auto at = [&](int xx, int yy) { return v[static_cast<size_t>(yy) * w + xx]; };
  const float top = at(x0, y0) + (at(x1, y0) - at(x0, y0)) * fx;
  const float bottom = at(x0, y1) + (at(x1, y1) - at(x0, y1)) * fx;
  return top + (bottom - top) * fy;
}

}  // namespace relief::lod
