#include "relief/lod/measured_error.h"

#include <algorithm>
#include <cmath>
#include <optional>
#include <random>

#include <fmt/format.h>

#include "relief/lod/mesh_evaluator.h"
#include "relief/lod/refined_evaluator.h"

namespace relief::lod {

Result<MeasuredError> measure_screen_error(const View& view, TerrainModel& terrain,
                                           const Selection& selection, const geo::GeoBox& extent,
                                           int samples, const RefinedMesh* refined) {
  MeshEvaluator mesh(terrain, selection);
  std::optional<RefinedEvaluator> refined_mesh;
  if (refined) refined_mesh.emplace(terrain, selection, *refined);
  std::mt19937 rng(5);
  const int finest = terrain.data_max_level();
  const double n = std::ldexp(1.0, finest);
  const int w = terrain.tile_width(), h = terrain.tile_height(), b = terrain.border();
  std::uniform_real_distribution<double> unit(0, 1);
  MeasuredError out;
  for (int s = 0; s < samples && !selection.quads.empty(); ++s) {
    const SelectedQuad& q = selection.quads[rng() % selection.quads.size()];
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
    const SelectedQuad* at = mesh.containing(slon, slat);
    if (!at) continue;
    if (!terrain.available(k)) continue;  // interactive frames: not resident, not drawn
    auto tile = RELIEF_TRY(terrain.tile(k));
    if (!tile) continue;  // no data: drawn at height 0 by both
    const double height =
        tile->f32()[static_cast<size_t>(j + b) * static_cast<size_t>(tile->width()) +
                    static_cast<size_t>(i + b)];
    Vec3 on_mesh;
    if (refined_mesh) {
      const std::optional<Vec3> p = RELIEF_TRY(refined_mesh->point(*at, slon, slat));
      if (!p)
        return fail(fmt::format("refined mesh: no triangle of quad {} holds {},{}",
                                at->key.to_string(), slon, slat));
      on_mesh = *p;
    } else {
      on_mesh = RELIEF_TRY(mesh.mesh_point(*at, slon, slat));
    }
    double ax, ay, bx, by;
    if (!view.project(ecef(slon, slat, height), ax, ay) || !view.project(on_mesh, bx, by)) continue;
    if (ax < 0 || ay < 0 || ax >= view.width || ay >= view.height) continue;
    out.max_pixels = std::max(out.max_pixels, std::hypot(ax - bx, ay - by));
    ++out.samples;
  }
  return out;
}

}  // namespace relief::lod
