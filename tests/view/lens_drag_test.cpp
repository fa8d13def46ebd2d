// Which lens a point on the ground grabs (view/lens_drag.h): inside the
// circle as the lens pass measures it, the nearest centre relative to its
// radius where circles overlap, across the antimeridian too.
#include <gtest/gtest.h>

#include <cmath>
#include <numbers>

#include "relief/view/lens_drag.h"

namespace relief::view {
namespace {

std::vector<render::TextureLayer> layers_with(std::vector<std::vector<render::Lens>> lenses) {
  std::vector<render::TextureLayer> layers(lenses.size());
  for (size_t i = 0; i < lenses.size(); ++i) layers[i].lenses = std::move(lenses[i]);
  return layers;
}

TEST(LensDrag, APointGrabsTheLensWhoseCircleHoldsIt) {
  // 1 km at 42 N: 1000 / (111319.49 cos 42) degrees of longitude.
  const double km_lon =
      1000 / (6378137.0 * std::numbers::pi / 180 * std::cos(42 * std::numbers::pi / 180));
  EXPECT_NEAR(lens_distance_m(1.5, 42, 1.5 + km_lon, 42), 1000, 1e-6);
  const auto layers = layers_with({{{1.5, 42, 1000, {}}}, {{1.5 + 1.5 * km_lon, 42, 1000, {}}}});
  EXPECT_EQ(lens_at(layers, 1.5 + 0.2 * km_lon, 42), (LensRef{0, 0}));
  // In both circles: the nearer centre relative to its radius.
  EXPECT_EQ(lens_at(layers, 1.5 + 0.9 * km_lon, 42), (LensRef{1, 0}));
  EXPECT_EQ(lens_at(layers, 1.5 + 0.7 * km_lon, 42), (LensRef{0, 0}));
  EXPECT_FALSE(lens_at(layers, 1.5 - 1.01 * km_lon, 42));
  EXPECT_FALSE(lens_at(layers, 1.5, 42.01));  // 1.1 km north
  // Across the antimeridian.
  const auto far = layers_with({{{179.999, 0, 500, {}}}});
  EXPECT_EQ(lens_at(far, -179.998, 0), (LensRef{0, 0}));  // 334 m east
}

}  // namespace
}  // namespace relief::view
