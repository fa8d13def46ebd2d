#include "relief/lod/mesh_evaluator.h"

#include <cmath>

namespace relief::lod {

MeshEvaluator::MeshEvaluator(TerrainModel& terrain, const Selection& selection)
    : terrain_(terrain) {
  for (const auto& q : selection.quads) quads_[q.key] = q;
}

const SelectedQuad* MeshEvaluator::containing(double lon, double lat) const {
  for (int l = terrain_.max_level(); l >= 0; --l) {
    const double n = std::ldexp(1.0, l);
    const geo::TileKey k{l, static_cast<uint32_t>((lon + 180) / 360 * n),
                         static_cast<uint32_t>((90 - lat) / 180 * n)};
    if (auto it = quads_.find(k); it != quads_.end()) return &it->second;
  }
  return nullptr;
}

Result<double> MeshEvaluator::vertex_height(const SelectedQuad& q, const MeshVertex& v) {
  const bool parent = (v.sides & q.parent_data_sides) || (v.corner & q.parent_data_corners);
  const DataWindow w = parent ? terrain_.parent_window(q.key) : terrain_.window(q.key);
  if (!w.tile) return 0.0;
  auto t = RELIEF_TRY(terrain_.tile(*w.tile));
  if (!t) return 0.0;
  return TerrainModel::bilinear(*t, terrain_.border(), w.x0 + v.u * w.width, w.y0 + v.v * w.height);
}

Result<Vec3> MeshEvaluator::mesh_point(const SelectedQuad& q, double lon, double lat) {
  const MeshTopology& m = terrain_.mesh();
  const geo::GeoBox b = q.key.bounds();
  const double u = (lon - b.west) / b.width(), v = (b.north - lat) / b.height();
  const uint32_t first = m.first_index(q.finer_sides), count = m.index_count(q.finer_sides);
  for (uint32_t t = first; t < first + count; t += 3) {
    const MeshVertex* p[3];
    for (int k = 0; k < 3; ++k) p[k] = &m.vertices()[m.indices()[t + k]];
    // Barycentric coordinates of (u, v) in the triangle, with a tolerance so
    // points on a shared edge belong to either side.
    const double d =
        (p[1]->u - p[0]->u) * (p[2]->v - p[0]->v) - (p[2]->u - p[0]->u) * (p[1]->v - p[0]->v);
    const double s =
        ((u - p[0]->u) * (p[2]->v - p[0]->v) - (p[2]->u - p[0]->u) * (v - p[0]->v)) / d;
    const double r =
        ((p[1]->u - p[0]->u) * (v - p[0]->v) - (u - p[0]->u) * (p[1]->v - p[0]->v)) / d;
    if (s < -1e-12 || r < -1e-12 || s + r > 1 + 1e-12) continue;
    Vec3 out;
    const double w[3] = {1 - s - r, s, r};
    for (int k = 0; k < 3; ++k) {
      const double plon = b.west + p[k]->u * b.width(), plat = b.north - p[k]->v * b.height();
      out = out + ecef(plon, plat, RELIEF_TRY(vertex_height(q, *p[k]))) * w[k];
    }
    return out;
  }
  return fail("mesh_point: no triangle of " + q.key.to_string() + " contains the point");
}

}  // namespace relief::lod
