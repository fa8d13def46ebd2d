#include "relief/view/lens_drag.h"

#include "relief/geo/tangent_plane.h"

namespace relief::view {

double lens_distance_m(double lon0, double lat0, double lon, double lat) {
  return geo::tangent_plane_distance_m(lon0, lat0, lon, lat);
}

std::optional<LensRef> lens_at(const std::vector<render::TextureLayer>& layers, double lon,
                               double lat) {
  std::optional<LensRef> best;
  double best_ratio = 1;
  for (size_t i = layers.size(); i-- > 0;) {  // the upper layers first
    for (size_t k = 0; k < layers[i].lenses.size(); ++k) {
      const render::Lens& lens = layers[i].lenses[k];
      if (!(lens.radius_m > 0)) continue;
      const double ratio = lens_distance_m(lens.lon, lens.lat, lon, lat) / lens.radius_m;
      if (ratio <= 1 && (!best || ratio < best_ratio)) best = LensRef{i, k}, best_ratio = ratio;
    }
  }
  return best;
}

}  // namespace relief::view
