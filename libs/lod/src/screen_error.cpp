#include "relief/lod/screen_error.h"

#include <algorithm>
#include <cmath>

namespace relief::lod {

namespace {

constexpr double kDegree = 3.14159265358979323846 / 180;
constexpr double kHalfPi = 3.14159265358979323846 / 2;

// Largest |sin| and |cos| of the angle between the view direction and any
// normal of the area: those within the normals' spread of the centre's.
//
// With the angle range [lo, hi] = [centre - spread, centre + spread] clamped
// to [0, pi], the sines and cosines of its ends follow from those of the
// centre (its cosine is the dot product) and of the spread by the angle-sum
// identities: no trigonometric call per view (an acos and four more before,
// a tenth of a quad selection's time).
void angle_bounds(const View& view, const AreaNormals& n, double& s, double& c) {
  const double cos_centre = std::clamp(dot(n.up, view.forward), -1.0, 1.0);
  const double sin_centre = std::sqrt(std::max(0.0, 1 - cos_centre * cos_centre));
  // lo > 0 when centre > spread, i.e. cos(centre) < cos(spread); hi < pi when
  // centre + spread < pi, i.e. cos(centre) > cos(pi - spread) = -cos(spread).
  double sin_lo = 0, cos_lo = 1, sin_hi = 0, cos_hi = -1;
  if (cos_centre < n.cos_spread) {
    sin_lo = sin_centre * n.cos_spread - cos_centre * n.sin_spread;
    cos_lo = cos_centre * n.cos_spread + sin_centre * n.sin_spread;
  }
  if (cos_centre > -n.cos_spread) {
    sin_hi = sin_centre * n.cos_spread + cos_centre * n.sin_spread;
    cos_hi = cos_centre * n.cos_spread - sin_centre * n.sin_spread;
  }
  // lo <= pi/2 <= hi: the range holds the right angle, where |sin| = 1.
  s = cos_lo >= 0 && cos_hi <= 0 ? 1.0 : std::max(sin_lo, sin_hi);
  c = std::max(std::abs(cos_lo), std::abs(cos_hi));
}

}  // namespace

AreaNormals area_normals(const geo::GeoBox& area) {
  // The normals lie within half the area's extent along a meridian plus
  // along a parallel of the centre's (at most pi: every direction).
  const double spread = std::min((area.width() + area.height()) / 2 * kDegree, 2 * kHalfPi);
  return {up_at((area.west + area.east) / 2, (area.south + area.north) / 2), std::cos(spread),
          std::sin(spread)};
}

VerticalErrorParts vertical_error_parts(const View& view, const Box& box, const geo::GeoBox& area,
                                        double metres) {
  if (metres <= 0) return {};
  return vertical_error_parts(view, box, area_normals(area), metres);
}

VerticalErrorParts vertical_error_parts(const View& view, const Box& box,
                                        const AreaNormals& normals, double metres) {
  VerticalErrorParts e;
  if (metres <= 0) return e;
  const double f = view.pixels_per_radian;
  const double corner = view.tan_half_x * view.tan_half_x + view.tan_half_y * view.tan_half_y;
  e.distance = distance_to(box, view.eye);
  e.distance_bound = e.distance > 0 ? f * metres * (1 + corner) / e.distance : INFINITY;
  e.pixels = e.distance_bound;
  double z_min = INFINITY, t = 0;
  for (int i = 0; i < 8; ++i) {
    const Vec3 p = Vec3{i & 1 ? box.hi.x : box.lo.x, i & 2 ? box.hi.y : box.lo.y,
                        i & 4 ? box.hi.z : box.lo.z} -
                   view.eye;
    const double z = dot(p, view.forward);
    if (z <= 0) {  // behind the eye: only the distance bound holds
      e.behind = true;
      return e;
    }
    z_min = std::min(z_min, z);
    const double x = dot(p, view.right), y = dot(p, view.up);
    t = std::max(t, std::sqrt(x * x + y * y) / z);
  }
  double s = 1, c = 1;
  angle_bounds(view, normals, s, c);
  e.z_min = z_min;
  e.tangent = t;
  e.sin_bound = s;
  e.cos_bound = c;
  e.pixels = std::min(e.distance_bound, f * metres * (s + t * c) / z_min);
  return e;
}

double vertical_error_pixels(const View& view, const Box& box, const geo::GeoBox& area,
                             double metres) {
  return vertical_error_parts(view, box, area, metres).pixels;
}

double vertical_error_pixels(const View& view, const Box& box, const AreaNormals& normals,
                             double metres) {
  return vertical_error_parts(view, box, normals, metres).pixels;
}

}  // namespace relief::lod
