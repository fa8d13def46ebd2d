#pragma once
// The screen-space error of a LOD selection, measured: finest samples
// projected from the data and from the LOD mesh as the vertex shader builds it
// (parent data on coarser sides and corners, split border triangles), the
// largest distance between the two in pixels. The same evaluation as
// tests/lod/error_bound_test.cpp (lod::MeshEvaluator), over random finest samples of the selected
// quads: a measured lower bound of the true maximum, to set against the
// selection's own upper bound.
#include <algorithm>
#include <cmath>
#include <random>

#include "relief/lod/mesh_evaluator.h"

namespace relief::bench {

class MeshError {
 public:
  MeshError(lod::TerrainModel& terrain, const lod::Selection& selection)
      : terrain_(terrain), mesh_(terrain, selection) {}

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
      const lod::SelectedQuad* at = mesh_.containing(slon, slat);
      if (!at) continue;
      auto tile = RELIEF_TRY(terrain_.tile(k));
      if (!tile) continue;  // no data: drawn at height 0 by both
      const double height =
          tile->f32()[static_cast<size_t>(j + b) * static_cast<size_t>(tile->width()) +
                      static_cast<size_t>(i + b)];
      const auto on_mesh = RELIEF_TRY(mesh_.mesh_point(*at, slon, slat));
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
  lod::TerrainModel& terrain_;
  lod::MeshEvaluator mesh_;
};

}  // namespace relief::bench
