#pragma once
// The screen-space error of a LOD selection, measured: finest samples
// projected from the data and from the LOD mesh as the vertex shader builds it
// (parent data on coarser sides and corners, split border triangles), the
// largest distance between the two in pixels. The same evaluation as
// tests/lod/error_bound_test.cpp, over random finest samples of the selected
// quads: a measured lower bound of the true maximum, to set against the
// selection's own upper bound.
#include <algorithm>
#include <cmath>
#include <random>
#include <unordered_map>

#include "relief/lod/selection.h"

namespace relief::bench {

class MeshError {
 public:
  MeshError(lod::TerrainModel& terrain, const lod::Selection& selection) : terrain_(terrain) {
    for (const auto& q : selection.quads) quads_[q.key] = q;
  }

  // Largest projected distance over `samples` random finest samples of the
  // selected quads inside the data's extent; the number compared (on
  // screen) in `compared`.
  Result<double> sampled_max(const lod::View& view, const lod::Selection& selection,
                             const geo::GeoBox& extent, int samples, size_t& compared) {
    std::mt19937 rng(5);
    const int finest = terrain_.data_max_level();
    const double n = std::ldexp(1.0, finest);
    const int w = terrain_.tile_width(), h = terrain_.tile_height(), b = terrain_.border();
    double worst = 0;
    compared = 0;
    std::uniform_real_distribution<double> unit(0, 1);
    for (int s = 0; s < samples && !selection.quads.empty(); ++s) {
      const lod::SelectedQuad& q = selection.quads[rng() % selection.quads.size()];
      const geo::GeoBox all = q.key.bounds();
      const geo::GeoBox qb{std::max(all.west, extent.west), std::max(all.south, extent.south),
                           std::min(all.east, extent.east), std::min(all.north, extent.north)};
      if (qb.west >= qb.east || qb.south >= qb.north) continue;  // no data: height 0 in both
      const double lon = qb.west + unit(rng) * qb.width(), lat = qb.north - unit(rng) * qb.height();
      const geo::TileKey k{finest, static_cast<uint32_t>((lon + 180) / 360 * n),
                           static_cast<uint32_t>((90 - lat) / 180 * n)};
      const geo::GeoBox kb = k.bounds();
      const int i = std::clamp(static_cast<int>((lon - kb.west) / kb.width() * w), 0, w - 1);
      const int j = std::clamp(static_cast<int>((kb.north - lat) / kb.height() * h), 0, h - 1);
      const double slon = kb.west + (i + 0.5) * kb.width() / w;
      const double slat = kb.north - (j + 0.5) * kb.height() / h;
      const lod::SelectedQuad* at = containing(slon, slat);
      if (!at) continue;
      auto tile = RELIEF_TRY(terrain_.tile(k));
      if (!tile) continue;  // no data: drawn at height 0 by both
      const double height =
          tile->f32()[static_cast<size_t>(j + b) * static_cast<size_t>(tile->width()) +
                      static_cast<size_t>(i + b)];
      const auto on_mesh = RELIEF_TRY(mesh_point(*at, slon, slat));
      double ax, ay, bx, by;
      if (!view.project(lod::ecef(slon, slat, height), ax, ay) || !view.project(on_mesh, bx, by))
        continue;
      if (ax < 0 || ay < 0 || ax >= view.width || ay >= view.height) continue;
      worst = std::max(worst, std::hypot(ax - bx, ay - by));
      ++compared;
    }
    return worst;
  }

 private:
  const lod::SelectedQuad* containing(double lon, double lat) const {
    for (int l = terrain_.max_level(); l >= 0; --l) {
      const double n = std::ldexp(1.0, l);
      const geo::TileKey k{l, static_cast<uint32_t>((lon + 180) / 360 * n),
                           static_cast<uint32_t>((90 - lat) / 180 * n)};
      if (auto it = quads_.find(k); it != quads_.end()) return &it->second;
    }
    return nullptr;
  }

  // Height of mesh vertex v of quad q, as the vertex shader computes it.
  Result<double> vertex_height(const lod::SelectedQuad& q, const lod::MeshVertex& v) {
    const bool parent = (v.sides & q.coarse_sides) || (v.corner & q.coarse_corners);
    const lod::DataWindow w = parent ? terrain_.parent_window(q.key) : terrain_.window(q.key);
    if (!w.tile) return 0.0;
    auto t = RELIEF_TRY(terrain_.tile(*w.tile));
    if (!t) return 0.0;
    return lod::TerrainModel::bilinear(*t, terrain_.border(), w.x0 + v.u * w.width,
                                       w.y0 + v.v * w.height);
  }

  // The mesh point above (lon, lat): the triangle's three vertices placed on
  // the ellipsoid with their heights, interpolated in 3-D.
  Result<lod::Vec3> mesh_point(const lod::SelectedQuad& q, double lon, double lat) {
    const lod::MeshTopology& m = terrain_.mesh();
    const geo::GeoBox b = q.key.bounds();
    const double u = (lon - b.west) / b.width(), v = (b.north - lat) / b.height();
    const uint32_t first = m.first_index(q.finer_sides), count = m.index_count(q.finer_sides);
    for (uint32_t t = first; t < first + count; t += 3) {
      const lod::MeshVertex* p[3];
      for (int k = 0; k < 3; ++k) p[k] = &m.vertices()[m.indices()[t + k]];
      const double d =
          (p[1]->u - p[0]->u) * (p[2]->v - p[0]->v) - (p[2]->u - p[0]->u) * (p[1]->v - p[0]->v);
      const double s =
          ((u - p[0]->u) * (p[2]->v - p[0]->v) - (p[2]->u - p[0]->u) * (v - p[0]->v)) / d;
      const double r =
          ((p[1]->u - p[0]->u) * (v - p[0]->v) - (u - p[0]->u) * (p[1]->v - p[0]->v)) / d;
      if (s < -1e-12 || r < -1e-12 || s + r > 1 + 1e-12) continue;
      lod::Vec3 out;
      const double w[3] = {1 - s - r, s, r};
      for (int k = 0; k < 3; ++k) {
        const double plon = b.west + p[k]->u * b.width(), plat = b.north - p[k]->v * b.height();
        out = out + lod::ecef(plon, plat, RELIEF_TRY(vertex_height(q, *p[k]))) * w[k];
      }
      return out;
    }
    return fail("mesh_error: no triangle of " + q.key.to_string() + " contains the point");
  }

  lod::TerrainModel& terrain_;
  std::unordered_map<geo::TileKey, lod::SelectedQuad, geo::TileKeyHash> quads_;
};

}  // namespace relief::bench
