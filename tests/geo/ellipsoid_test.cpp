#include "relief/geo/ellipsoid.h"

#include <gtest/gtest.h>

#include <random>

namespace relief::geo {

TEST(Ellipsoid, KnownPoints) {
  const Ecef equator = to_ecef({0, 0, 0});
  EXPECT_DOUBLE_EQ(equator.x, wgs84::kSemiMajorAxis);
  EXPECT_NEAR(equator.y, 0, 1e-9);
  const Ecef pole = to_ecef({0, 90, 0});
  EXPECT_NEAR(pole.z, wgs84::kSemiMinorAxis, 1e-6);
  EXPECT_NEAR(pole.x, 0, 1e-6);
  const Ecef east = to_ecef({90, 0, 100});
  EXPECT_NEAR(east.y, wgs84::kSemiMajorAxis + 100, 1e-6);
}

TEST(Ellipsoid, RoundTripIsSubMillimetre) {
  std::mt19937_64 rng(42);
  std::uniform_real_distribution<double> lon(-180, 180), lat(-89.999, 89.999), h(-500, 1e7);
  for (int i = 0; i < 10000; ++i) {
    const Geodetic g{lon(rng), lat(rng), h(rng)};
    const Geodetic back = to_geodetic(to_ecef(g));
    EXPECT_NEAR(back.lon_deg, g.lon_deg, 1e-10);
    EXPECT_NEAR(back.lat_deg, g.lat_deg, 1e-10);
    EXPECT_NEAR(back.height_m, g.height_m, 1e-4);
  }
}

}  // namespace relief::geo
