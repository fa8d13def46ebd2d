#include "mesh_error.h"

#include <algorithm>
#include <cmath>
#include <vector>

#include "relief/lod/terrain_model.h"

namespace relief::lod {
namespace {

// Height at (a, b) in [0,1]^2 of a triangle with local vertices p[3] and heights h[3].
double interpolate(double a, double b, const double (*p)[2], const double* h) {
  const double d =
      (p[1][0] - p[0][0]) * (p[2][1] - p[0][1]) - (p[2][0] - p[0][0]) * (p[1][1] - p[0][1]);
  const double s = ((a - p[0][0]) * (p[2][1] - p[0][1]) - (p[2][0] - p[0][0]) * (b - p[0][1])) / d;
  const double t = ((p[1][0] - p[0][0]) * (b - p[0][1]) - (a - p[0][0]) * (p[1][1] - p[0][1])) / d;
  return h[0] * (1 - s - t) + h[1] * s + h[2] * t;
}

}  // namespace

double mesh_sample_error(const MeshTopology& m, const tiles::Raster& t, int border,
                         const DataWindow& w) {
  const int nx = m.squares_x(), ny = m.squares_y();
  std::vector<double> vh(m.vertices().size());
  for (size_t i = 0; i < vh.size(); ++i) {
    const MeshVertex& v = m.vertices()[i];
    vh[i] = TerrainModel::bilinear(t, border, w.x0 + v.u * w.width, w.y0 + v.v * w.height);
  }
  double worst = 0;
  const int i0 = static_cast<int>(w.x0), j0 = static_cast<int>(w.y0);
  const int iw = static_cast<int>(w.width), jh = static_cast<int>(w.height);
  const auto data = t.f32();
  static constexpr double kC[2] = {0.5, 0.5};
  for (int j = j0; j < j0 + jh; ++j) {
    for (int i = i0; i < i0 + iw; ++i) {
      const double value = data[static_cast<size_t>(j + border) * t.width() + i + border];
      const double u = (i + 0.5 - w.x0) / w.width * nx, v = (j + 0.5 - w.y0) / w.height * ny;
      const int si = std::min(nx - 1, static_cast<int>(u)),
                sj = std::min(ny - 1, static_cast<int>(v));
      const double a = u - si, b = v - sj;
      const double hc = vh[m.centre_vertex(si, sj)];
      const double hnw = vh[m.corner_vertex(si, sj)], hne = vh[m.corner_vertex(si + 1, sj)];
      const double hsw = vh[m.corner_vertex(si, sj + 1)], hse = vh[m.corner_vertex(si + 1, sj + 1)];
      // The triangle of the square containing (a, b), and its side if on the border.
      double p[3][2], h[3];
      int side = 0, k = 0;
      double mid[2];
      if (b <= a && b <= 1 - a) {
        p[0][0] = 0, p[0][1] = 0, p[1][0] = 1, p[1][1] = 0, h[0] = hnw, h[1] = hne;
        side = sj == 0 ? kNorth : 0, k = si, mid[0] = 0.5, mid[1] = 0;
      } else if (a >= b && a >= 1 - b) {
        p[0][0] = 1, p[0][1] = 0, p[1][0] = 1, p[1][1] = 1, h[0] = hne, h[1] = hse;
        side = si == nx - 1 ? kEast : 0, k = sj, mid[0] = 1, mid[1] = 0.5;
      } else if (b >= a && b >= 1 - a) {
        p[0][0] = 1, p[0][1] = 1, p[1][0] = 0, p[1][1] = 1, h[0] = hse, h[1] = hsw;
        side = sj == ny - 1 ? kSouth : 0, k = si, mid[0] = 0.5, mid[1] = 1;
      } else {
        p[0][0] = 0, p[0][1] = 1, p[1][0] = 0, p[1][1] = 0, h[0] = hsw, h[1] = hnw;
        side = si == 0 ? kWest : 0, k = sj, mid[0] = 0, mid[1] = 0.5;
      }
      p[2][0] = kC[0], p[2][1] = kC[1], h[2] = hc;
      worst = std::max(worst, std::abs(interpolate(a, b, p, h) - value));
      if (side) {  // the split variant: two triangles through the side's midpoint
        const double hm = vh[m.side_midpoint(side, k)];
        double q[3][2] = {{p[0][0], p[0][1]}, {mid[0], mid[1]}, {kC[0], kC[1]}};
        double hq[3] = {h[0], hm, hc};
        const bool first_half = (a - p[0][0]) * (a - p[0][0]) + (b - p[0][1]) * (b - p[0][1]) <=
                                (a - p[1][0]) * (a - p[1][0]) + (b - p[1][1]) * (b - p[1][1]);
        if (!first_half) {
          q[0][0] = mid[0], q[0][1] = mid[1], q[1][0] = p[1][0], q[1][1] = p[1][1];
          hq[0] = hm, hq[1] = h[1];
        }
        worst = std::max(worst, std::abs(interpolate(a, b, q, hq) - value));
      }
    }
  }
  return worst;
}

}  // namespace relief::lod
