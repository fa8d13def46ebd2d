#pragma once
// The LOD mesh of a selection evaluated from scratch, as the vertex shader
// builds it (parent data on coarser sides and corners, split border
// triangles), independently of the selection's error estimate: what the
// error-bound tests and bench/render measure the estimate against.
#include <unordered_map>

#include "relief/lod/selection.h"

namespace relief::lod {

class MeshEvaluator {
 public:
  MeshEvaluator(TerrainModel& terrain, const Selection& selection);

  // The selected quad whose area holds (lon, lat), finest level first;
  // null where the selection has none (culled).
  const SelectedQuad* containing(double lon, double lat) const;
  // Height of mesh vertex `v` of quad `q`, as the vertex shader computes it
  // (0 where there is no data).
  Result<double> vertex_height(const SelectedQuad& q, const MeshVertex& v);
  // The mesh point above (lon, lat) inside `q`: its triangle's three vertices
  // placed on the ellipsoid with their heights, interpolated in 3-D.
  Result<Vec3> mesh_point(const SelectedQuad& q, double lon, double lat);

 private:
  TerrainModel& terrain_;
  std::unordered_map<geo::TileKey, SelectedQuad, geo::TileKeyHash> quads_;
};

}  // namespace relief::lod
