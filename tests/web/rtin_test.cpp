// The RTIN's meshes: within the error everywhere, conforming, in map
// winding, numbered by first use.
#include <gtest/gtest.h>

#include <cmath>
#include <map>
#include <random>

#include "relief/web/rtin.h"

namespace relief::web {
namespace {

std::vector<float> rough_lattice(int size, unsigned seed) {
  std::mt19937 random(seed);
  std::normal_distribution<float> noise(0, 25);
  std::vector<float> h(static_cast<size_t>(size) * size);
  for (int y = 0; y < size; ++y) {
    for (int x = 0; x < size; ++x) {
      h[static_cast<size_t>(y) * size + x] =
          2000 * std::exp(-((x - 90.0f) * (x - 90.0f) + (y - 160.0f) * (y - 160.0f)) / 3000) +
          (x > 200 ? 300.0f : 0.0f) + noise(random);
    }
  }
  return h;
}

struct Checked {
  double worst = 0;  // largest |mesh - lattice|
  double area = 0;   // twice the triangles' summed area
};

// Every lattice point inside each triangle against the triangle's plane.
Checked check_mesh(const RtinMesh& mesh, const std::vector<float>& h, int size) {
  Checked c;
  std::vector<int> covered(h.size(), 0);
  for (size_t t = 0; t < mesh.triangle_count(); ++t) {
    int px[3], py[3];
    double ph[3];
    for (int k = 0; k < 3; ++k) {
      const uint32_t v = mesh.triangles[3 * t + k];
      px[k] = mesh.xy[2 * v], py[k] = mesh.xy[2 * v + 1];
      ph[k] = h[static_cast<size_t>(py[k]) * size + px[k]];
    }
    // Counter-clockwise on a map: y grows south, so the lattice's cross
    // product is negative.
    const double cross =
        double(px[1] - px[0]) * (py[2] - py[0]) - double(py[1] - py[0]) * (px[2] - px[0]);
    EXPECT_LT(cross, 0) << "triangle " << t;
    c.area += -cross;
    for (int y = std::min({py[0], py[1], py[2]}); y <= std::max({py[0], py[1], py[2]}); ++y) {
      for (int x = std::min({px[0], px[1], px[2]}); x <= std::max({px[0], px[1], px[2]}); ++x) {
        const double w0 = double(px[1] - x) * (py[2] - y) - double(py[1] - y) * (px[2] - x);
        const double w1 = double(px[2] - x) * (py[0] - y) - double(py[2] - y) * (px[0] - x);
        const double w2 = double(px[0] - x) * (py[1] - y) - double(py[0] - y) * (px[1] - x);
        if (w0 > 0 || w1 > 0 || w2 > 0) continue;  // outside (all <= 0 inside)
        const double at = (w0 * ph[0] + w1 * ph[1] + w2 * ph[2]) / (w0 + w1 + w2);
        c.worst = std::max(c.worst, std::abs(at - h[static_cast<size_t>(y) * size + x]));
        ++covered[static_cast<size_t>(y) * size + x];
      }
    }
  }
  for (size_t i = 0; i < covered.size(); ++i) EXPECT_GT(covered[i], 0) << "point " << i;
  return c;
}

TEST(Rtin, MeshesStayWithinTheirErrorAndCoverTheTile) {
  Rtin rtin(8);
  const int size = rtin.size();
  const auto h = rough_lattice(size, 11);
  std::vector<float> errors(h.size(), 0);
  rtin.accumulate_errors(h, errors);
  size_t previous = 0;
  for (const float max_error : {500.0f, 100.0f, 20.0f, 5.0f, 0.0f}) {
    const RtinMesh mesh = rtin.mesh(errors, max_error);
    const Checked c = check_mesh(mesh, h, size);
    EXPECT_LE(c.worst, max_error + 1e-3) << "max_error " << max_error;
    EXPECT_DOUBLE_EQ(c.area, 2.0 * 256 * 256);
    EXPECT_GT(mesh.vertex_count(), previous) << "finer errors keep more vertices";
    previous = mesh.vertex_count();
  }
  EXPECT_EQ(previous, 257u * 257u);
}

TEST(Rtin, MeshesConformEveryInnerEdgeHasTwoTriangles) {
  Rtin rtin(8);
  const auto h = rough_lattice(rtin.size(), 5);
  std::vector<float> errors(h.size(), 0);
  rtin.accumulate_errors(h, errors);
  const RtinMesh mesh = rtin.mesh(errors, 15);
  std::map<std::pair<uint32_t, uint32_t>, int> edges;
  for (size_t t = 0; t < mesh.triangle_count(); ++t) {
    for (int k = 0; k < 3; ++k) {
      const uint32_t a = mesh.triangles[3 * t + k], b = mesh.triangles[3 * t + (k + 1) % 3];
      ++edges[{std::min(a, b), std::max(a, b)}];
    }
  }
  const auto on_boundary = [&](uint32_t a, uint32_t b) {
    const int ax = mesh.xy[2 * a], ay = mesh.xy[2 * a + 1], bx = mesh.xy[2 * b],
              by = mesh.xy[2 * b + 1];
    return (ax == bx && (ax == 0 || ax == 256)) || (ay == by && (ay == 0 || ay == 256));
  };
  for (const auto& [edge, count] : edges) {
    // A T-junction would leave the long edge with one triangle.
    EXPECT_EQ(count, on_boundary(edge.first, edge.second) ? 1 : 2);
  }
}

TEST(Rtin, VerticesAreNumberedByFirstUse) {
  Rtin rtin(6);
  const auto h = rough_lattice(rtin.size(), 2);
  std::vector<float> errors(h.size(), 0);
  rtin.accumulate_errors(h, errors);
  const RtinMesh mesh = rtin.mesh(errors, 10);
  uint32_t next = 0;
  for (const uint32_t i : mesh.triangles) {
    ASSERT_LE(i, next);
    if (i == next) ++next;
  }
  EXPECT_EQ(next, mesh.vertex_count());
}

TEST(Rtin, PresetBoundaryErrorsForceTheSameSplitsAlongAnEdge) {
  // Two lattices side by side sharing a column; each seeded with the other's
  // errors on it cut that column at the same points.
  Rtin rtin(8);
  const int size = rtin.size();
  const auto wide = rough_lattice(2 * size - 1, 9);
  std::vector<float> left(static_cast<size_t>(size) * size), right(left.size());
  for (int y = 0; y < size; ++y) {
    for (int x = 0; x < size; ++x) {
      left[static_cast<size_t>(y) * size + x] = wide[static_cast<size_t>(y) * (2 * size - 1) + x];
      right[static_cast<size_t>(y) * size + x] =
          wide[static_cast<size_t>(y) * (2 * size - 1) + x + 256];
    }
  }
  std::vector<float> plain_left(left.size(), 0), plain_right(left.size(), 0);
  rtin.accumulate_errors(left, plain_left);
  rtin.accumulate_errors(right, plain_right);
  std::vector<float> seeded_left(left.size(), 0), seeded_right(left.size(), 0);
  for (int y = 0; y < size; ++y) {
    seeded_left[static_cast<size_t>(y) * size + 256] = plain_right[static_cast<size_t>(y) * size];
    seeded_right[static_cast<size_t>(y) * size] = plain_left[static_cast<size_t>(y) * size + 256];
  }
  rtin.accumulate_errors(left, seeded_left);
  rtin.accumulate_errors(right, seeded_right);
  const auto column = [](const RtinMesh& m, int x) {
    std::vector<int> ys;
    for (size_t i = 0; i < m.vertex_count(); ++i) {
      if (m.xy[2 * i] == x) ys.push_back(m.xy[2 * i + 1]);
    }
    std::sort(ys.begin(), ys.end());
    return ys;
  };
  int differed_unseeded = 0;
  for (const float e : {200.0f, 40.0f, 12.0f}) {
    EXPECT_EQ(column(rtin.mesh(seeded_left, e), 256), column(rtin.mesh(seeded_right, e), 0)) << e;
    differed_unseeded +=
        column(rtin.mesh(plain_left, e), 256) != column(rtin.mesh(plain_right, e), 0);
  }
  EXPECT_GT(differed_unseeded, 0) << "the fixture must need the seeding";
}

}  // namespace
}  // namespace relief::web
