#include "mesh_error.h"

#include <algorithm>
#include <cmath>
#include <vector>

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

// The mesh of one quad with its vertices' heights, evaluated at points.
class MeshHeights {
 public:
  MeshHeights(const MeshTopology& m, const tiles::Raster& t, int border, const DataWindow& w)
      : m_(m), w_(w), heights_(m.vertices().size()) {
    for (size_t i = 0; i < heights_.size(); ++i) {
      const MeshVertex& v = m.vertices()[i];
      heights_[i] = bilinear_height(t, border, w.x0 + v.u * w.width, w.y0 + v.v * w.height);
    }
  }

  // max |mesh - value| at window sample coordinates (x, y), for the plain
  // triangle and, on the quad's border, the split variant.
  double error_at(double x, double y, double value) const {
    const int nx = m_.squares_x(), ny = m_.squares_y();
    const double u = (x - w_.x0) / w_.width * nx, v = (y - w_.y0) / w_.height * ny;
    const int si = std::clamp(static_cast<int>(u), 0, nx - 1);
    const int sj = std::clamp(static_cast<int>(v), 0, ny - 1);
    const double a = u - si, b = v - sj;
    const double hc = h(m_.centre_vertex(si, sj));
    const double hnw = h(m_.corner_vertex(si, sj)), hne = h(m_.corner_vertex(si + 1, sj));
    const double hsw = h(m_.corner_vertex(si, sj + 1)), hse = h(m_.corner_vertex(si + 1, sj + 1));
    static constexpr double kC[2] = {0.5, 0.5};
    // The triangle of the square containing (a, b), and its side if on the border.
    double p[3][2], hv[3];
    int side = 0, k = 0;
    double mid[2];
    if (b <= a && b <= 1 - a) {
      p[0][0] = 0, p[0][1] = 0, p[1][0] = 1, p[1][1] = 0, hv[0] = hnw, hv[1] = hne;
      side = sj == 0 ? kNorth : 0, k = si, mid[0] = 0.5, mid[1] = 0;
    } else if (a >= b && a >= 1 - b) {
      p[0][0] = 1, p[0][1] = 0, p[1][0] = 1, p[1][1] = 1, hv[0] = hne, hv[1] = hse;
      side = si == nx - 1 ? kEast : 0, k = sj, mid[0] = 1, mid[1] = 0.5;
    } else if (b >= a && b >= 1 - a) {
      p[0][0] = 1, p[0][1] = 1, p[1][0] = 0, p[1][1] = 1, hv[0] = hse, hv[1] = hsw;
      side = sj == ny - 1 ? kSouth : 0, k = si, mid[0] = 0.5, mid[1] = 1;
    } else {
      p[0][0] = 0, p[0][1] = 1, p[1][0] = 0, p[1][1] = 0, hv[0] = hsw, hv[1] = hnw;
      side = si == 0 ? kWest : 0, k = sj, mid[0] = 0, mid[1] = 0.5;
    }
    p[2][0] = kC[0], p[2][1] = kC[1], hv[2] = hc;
    double worst = std::abs(interpolate(a, b, p, hv) - value);
    if (side) {  // the split variant: two triangles through the side's midpoint
      const double hm = h(m_.side_midpoint(side, k));
      double q[3][2] = {{p[0][0], p[0][1]}, {mid[0], mid[1]}, {kC[0], kC[1]}};
      double hq[3] = {hv[0], hm, hc};
      const bool first_half = (a - p[0][0]) * (a - p[0][0]) + (b - p[0][1]) * (b - p[0][1]) <=
                              (a - p[1][0]) * (a - p[1][0]) + (b - p[1][1]) * (b - p[1][1]);
      if (!first_half) {
        q[0][0] = mid[0], q[0][1] = mid[1], q[1][0] = p[1][0], q[1][1] = p[1][1];
        hq[0] = hm, hq[1] = hv[1];
      }
      worst = std::max(worst, std::abs(interpolate(a, b, q, hq) - value));
    }
    return worst;
  }

 private:
  double h(uint32_t vertex) const { return heights_[vertex]; }
  const MeshTopology& m_;
  const DataWindow& w_;
  std::vector<double> heights_;
};

}  // namespace

double mesh_sample_error(const MeshTopology& m, const tiles::Raster& t, int border,
                         const DataWindow& w, bool full_mesh) {
  const MeshHeights mesh(m, t, border, w);
  const int i0 = static_cast<int>(w.x0), j0 = static_cast<int>(w.y0);
  const int iw = static_cast<int>(w.width), jh = static_cast<int>(w.height);
  const auto data = t.f32();
  double worst = 0;
  for (int j = j0; j < j0 + jh; ++j) {
    for (int i = i0; i < i0 + iw; ++i) {
      const double value = data[static_cast<size_t>(j + border) * t.width() + i + border];
      worst = std::max(worst, mesh.error_at(i + 0.5, j + 0.5, value));
    }
  }
  if (!full_mesh) return worst;
  // The sample corners of the full mesh (bilinear means of four samples).
  for (int j = j0; j <= j0 + jh; ++j) {
    for (int i = i0; i <= i0 + iw; ++i) {
      worst = std::max(worst, mesh.error_at(i, j, bilinear_height(t, border, i, j)));
    }
  }
  // Split border triangles of one-sample squares put vertices halfway along
  // cell sides, where the full mesh is the mean of the two corners.
  auto side_midpoint = [&](double x, double y, double ax, double ay, double bx, double by) {
    const double value =
        0.5 * (bilinear_height(t, border, ax, ay) + bilinear_height(t, border, bx, by));
    worst = std::max(worst, mesh.error_at(x, y, value));
  };
  for (int i = i0; i < i0 + iw; ++i) {
    side_midpoint(i + 0.5, j0, i, j0, i + 1, j0);
    side_midpoint(i + 0.5, j0 + jh, i, j0 + jh, i + 1, j0 + jh);
  }
  for (int j = j0; j < j0 + jh; ++j) {
    side_midpoint(i0, j + 0.5, i0, j, i0, j + 1);
    side_midpoint(i0 + iw, j + 0.5, i0 + iw, j, i0 + iw, j + 1);
  }
  return worst;
}

}  // namespace relief::lod
