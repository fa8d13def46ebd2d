#pragma once
// A refined mesh (lod/refine.h) evaluated from scratch as the renderer draws
// it: vertex heights as the vertex shader computes them (parent data on
// coarser sides and corners, lod::MeshEvaluator), the triangle above a point
// found by descending the 4-8 hierarchy of the quad's grid to a triangle of
// the mesh. What the guarantee tests and `--stats`'s measured error use.
#include <optional>
#include <unordered_map>
#include <unordered_set>
#include <vector>

#include "relief/lod/mesh_evaluator.h"
#include "relief/lod/refined_mesh.h"

namespace relief::lod {

struct GridPos {
  int x = 0, y = 0;
};

class RefinedEvaluator {
 public:
  // `selection` and `mesh` must outlive the evaluator.
  RefinedEvaluator(TerrainModel& terrain, const Selection& selection, const RefinedMesh& mesh);

  GridPos pos(uint32_t id) const;
  uint32_t id(GridPos p) const;
  // Lon/lat of grid point p of quad q (exact: dyadic fractions).
  std::pair<double, double> lonlat(const SelectedQuad& q, GridPos p) const;
  // Height of grid point p of quad q as the vertex shader computes it.
  Result<double> height(const SelectedQuad& q, GridPos p);
  const SelectedQuad* containing(double lon, double lat) const {
    return eval_.containing(lon, lat);
  }
  // The mesh point above (lon, lat) in quad q; nullopt when no triangle of
  // the mesh holds it (a malformed mesh).
  Result<std::optional<Vec3>> point(const SelectedQuad& q, double lon, double lat);

 private:
  const RefinedMesh& mesh_;
  MeshEvaluator eval_;
  int n_;
  std::vector<std::unordered_set<uint64_t>> triangles_;
  std::unordered_map<geo::TileKey, size_t, geo::TileKeyHash> index_;
};

}  // namespace relief::lod
