// The quantized-mesh encoder read back by the specification's reader
// (qm_decoder.h), Cesium's oct encoding and horizon occlusion point.
#include <gtest/gtest.h>

#include <cmath>
#include <random>

#include "qm_decoder.h"
#include "relief/web/quantized_mesh.h"
#include "relief/web/rtin.h"

namespace relief::web {
namespace {

using testing::decode_quantized_mesh;
using testing::gunzip;

// A mesh of a noisy lattice, as the tiler would build it (u east, v north).
QuantizedMeshInput noisy_tile(float max_error, bool normals) {
  Rtin rtin(8);
  const int size = rtin.size();
  std::mt19937 random(7);
  std::uniform_real_distribution<float> noise(-40, 40);
  std::vector<float> heights(static_cast<size_t>(size) * size);
  for (int y = 0; y < size; ++y) {
    for (int x = 0; x < size; ++x) {
      heights[static_cast<size_t>(y) * size + x] =
          1500 + 800 * std::sin(x * 0.03f) * std::cos(y * 0.05f) + noise(random);
    }
  }
  std::vector<float> errors(heights.size(), 0);
  rtin.accumulate_errors(heights, errors);
  const RtinMesh mesh = rtin.mesh(errors, max_error);
  QuantizedMeshInput in;
  in.rect = {1.40625, 42.1875, 1.58203125, 42.36328125};
  in.triangles = mesh.triangles;
  for (size_t i = 0; i < mesh.vertex_count(); ++i) {
    const int x = mesh.xy[2 * i], y = mesh.xy[2 * i + 1];
    in.u.push_back(static_cast<uint16_t>((x * 32767 + 128) >> 8));
    in.v.push_back(static_cast<uint16_t>(((256 - y) * 32767 + 128) >> 8));
    in.height.push_back(heights[static_cast<size_t>(y) * size + x]);
    if (normals) in.normals.push_back(geo::Ecef{0.6, 0, 0.8});
  }
  return in;
}

void expect_round_trip(const QuantizedMeshInput& in, bool wide) {
  const auto bytes = gzip(encode_quantized_mesh(in));
  ASSERT_GT(bytes.size(), 2u);
  EXPECT_EQ(bytes[0], std::byte{0x1f});
  EXPECT_EQ(bytes[1], std::byte{0x8b});
  const auto m = decode_quantized_mesh(gunzip(bytes));
  EXPECT_EQ(m.wide_indices, wide);
  EXPECT_EQ(m.u, in.u);
  EXPECT_EQ(m.v, in.v);
  EXPECT_EQ(m.indices, in.triangles);
  const auto [lo, hi] = std::minmax_element(in.height.begin(), in.height.end());
  EXPECT_EQ(m.min_height, *lo);
  EXPECT_EQ(m.max_height, *hi);
  const double half_step = (*hi - *lo) / 32767.0 / 2;
  for (size_t i = 0; i < in.u.size(); ++i) {
    ASSERT_NEAR(m.height(i), in.height[i], half_step * 1.0001) << "vertex " << i;
  }
  // Each edge lists exactly the vertices on it.
  size_t west = 0, south = 0, east = 0, north = 0;
  for (size_t i = 0; i < in.u.size(); ++i) {
    west += in.u[i] == 0, east += in.u[i] == 32767, south += in.v[i] == 0,
        north += in.v[i] == 32767;
  }
  EXPECT_EQ(m.west.size(), west);
  EXPECT_EQ(m.south.size(), south);
  EXPECT_EQ(m.east.size(), east);
  EXPECT_EQ(m.north.size(), north);
  for (uint32_t i : m.west) EXPECT_EQ(m.u[i], 0);
  for (uint32_t i : m.south) EXPECT_EQ(m.v[i], 0);
  for (uint32_t i : m.east) EXPECT_EQ(m.u[i], 32767);
  for (uint32_t i : m.north) EXPECT_EQ(m.v[i], 32767);
  EXPECT_EQ(m.normals.size(), in.normals.size() * 2);
  EXPECT_EQ(m.extensions, in.normals.empty() ? 0 : 1);
  // The bounding sphere holds every decoded vertex.
  for (size_t i = 0; i < in.u.size(); ++i) {
    const geo::Ecef p =
        geo::to_ecef({in.rect.west + m.u[i] / 32767.0 * in.rect.width(),
                      in.rect.south + m.v[i] / 32767.0 * in.rect.height(), m.height(i)});
    const double d = std::hypot(p.x - m.sphere[0], p.y - m.sphere[1], p.z - m.sphere[2]);
    ASSERT_LE(d, m.sphere[3] * (1 + 1e-12));
  }
}

TEST(QuantizedMesh, ASimplifiedMeshReadsBackWithSixteenBitIndices) {
  const auto in = noisy_tile(30, true);
  ASSERT_LT(in.u.size(), 65536u);
  expect_round_trip(in, false);
}

TEST(QuantizedMesh, TheFullLatticeNeedsThirtyTwoBitIndicesAfterTwoBytesOfPadding) {
  const auto in = noisy_tile(0, false);
  ASSERT_EQ(in.u.size(), 257u * 257u);
  ASSERT_EQ((92 + 6 * in.u.size()) % 4, 2u);  // the padded case
  expect_round_trip(in, true);
}

TEST(QuantizedMesh, MetadataTravelsAsExtensionFour) {
  auto in = noisy_tile(100, true);
  in.metadata_json = R"({"available":[]})";
  const auto m = decode_quantized_mesh(gunzip(gzip(encode_quantized_mesh(in))));
  EXPECT_EQ(m.extensions, 2);
  EXPECT_EQ(m.metadata, *in.metadata_json);
}

TEST(QuantizedMesh, OctEncodingMatchesCesiumsCheckValues) {
  const auto encode = [](geo::Ecef n) {
    uint8_t x = 0, y = 0;
    oct_encode(n, x, y);
    return std::pair<int, int>{x, y};
  };
  EXPECT_EQ(encode({0, 0, 1}), (std::pair{128, 128}));
  EXPECT_EQ(encode({0, 0, -1}), (std::pair{255, 255}));
  EXPECT_EQ(encode({1, 0, 0}), (std::pair{255, 128}));
  EXPECT_EQ(encode({-1, 0, 0}), (std::pair{0, 128}));
  EXPECT_EQ(encode({0, 1, 0}), (std::pair{128, 255}));
  EXPECT_EQ(encode({0, -1, 0}), (std::pair{128, 0}));
}

TEST(QuantizedMesh, CesiumsLevelErrorHalvesFrom77KilometresAtLevelZero) {
  EXPECT_NEAR(cesium_level_error(0), 77067.34, 0.01);
  EXPECT_NEAR(cesium_level_error(10), 75.261, 0.001);
}

// CesiumJS's EllipsoidalOccluder.isScaledSpacePointVisible, transcribed.
bool occluded(const geo::Ecef& point_scaled, const geo::Ecef& camera_scaled) {
  const double vh2 = camera_scaled.x * camera_scaled.x + camera_scaled.y * camera_scaled.y +
                     camera_scaled.z * camera_scaled.z - 1;
  const geo::Ecef vt{point_scaled.x - camera_scaled.x, point_scaled.y - camera_scaled.y,
                     point_scaled.z - camera_scaled.z};
  const double vt_dot_vc =
      -(vt.x * camera_scaled.x + vt.y * camera_scaled.y + vt.z * camera_scaled.z);
  const double vt2 = vt.x * vt.x + vt.y * vt.y + vt.z * vt.z;
  return vh2 < 0 ? vt_dot_vc > 0 : vt_dot_vc > vh2 && vt_dot_vc * vt_dot_vc / vt2 > vh2;
}

geo::Ecef scaled(const geo::Ecef& p) {
  return {p.x / geo::wgs84::kSemiMajorAxis, p.y / geo::wgs84::kSemiMajorAxis,
          p.z / geo::wgs84::kSemiMinorAxis};
}

TEST(QuantizedMesh, WhereTheHorizonHidesTheOcclusionPointItHidesEveryVertex) {
  std::mt19937 random(3);
  std::uniform_real_distribution<double> unit(0, 1);
  for (const geo::GeoBox box : {geo::GeoBox{1.40625, 42.1875, 1.58203125, 42.36328125},
                                geo::GeoBox{0, 0, 45, 45}, geo::GeoBox{-90, -90, 0, 0}}) {
    std::vector<geo::Ecef> points;
    for (int i = 0; i < 500; ++i) {
      points.push_back(
          geo::to_ecef({box.west + unit(random) * box.width(),
                        box.south + unit(random) * box.height(), -100 + unit(random) * 8000}));
    }
    const auto hop = horizon_occlusion_point(
        points, geo::to_ecef({(box.west + box.east) / 2, (box.south + box.north) / 2, 0}));
    ASSERT_TRUE(hop.has_value());
    int hidden = 0;
    for (int c = 0; c < 10000; ++c) {
      const geo::Ecef camera = scaled(geo::to_ecef(
          {unit(random) * 360 - 180, unit(random) * 180 - 90, 100 * std::pow(1e5, unit(random))}));
      if (!occluded(*hop, camera)) continue;
      ++hidden;
      for (const geo::Ecef& p : points) {
        // Cesium counts points below the ellipsoid as on it.
        ASSERT_TRUE(occluded(scaled(p), camera) || geo::to_geodetic(p).height_m < 0);
      }
    }
    EXPECT_GT(hidden, 1000) << "the test must see hidden tiles";
  }
}

TEST(QuantizedMesh, AHemisphereHasNoOcclusionPoint) {
  std::vector<geo::Ecef> points;
  for (double lon = -180; lon <= 0; lon += 10) {
    for (double lat = -90; lat <= 90; lat += 10) points.push_back(geo::to_ecef({lon, lat, 0}));
  }
  EXPECT_FALSE(horizon_occlusion_point(points, geo::to_ecef({-90, 0, 0})).has_value());
}

TEST(QuantizedMesh, GzipIsDeterministic) {
  const auto in = noisy_tile(50, true);
  EXPECT_EQ(gzip(encode_quantized_mesh(in)), gzip(encode_quantized_mesh(in)));
}

}  // namespace
}  // namespace relief::web
