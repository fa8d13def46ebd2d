#pragma once
// The screen-space error of a frame's mesh, measured rather than bounded:
// finest samples projected from the data and from the mesh as the vertex
// shader builds it (lod::MeshEvaluator), the largest distance between the two
// in pixels, over random finest samples of the selected quads that land on
// screen. A lower bound of the true maximum, to set against the selection's
// upper bound: what `relief render --stats` and bench/render report. Only the
// samples the guarantee covers count (docs/store-format.md): not nodata, and
// above the store's finest level not where the drawn level's full mesh
// reaches nodata (the fall-off at the data's edge and at voids).
#include <cstddef>
#include <optional>
#include <span>
#include <vector>

#include "relief/base/result.h"
#include "relief/geo/tile_key.h"
#include "relief/lod/refined_mesh.h"
#include "relief/lod/selection.h"

namespace relief::lod {

struct MeasuredError {
  double max_pixels = 0;
  size_t samples = 0;  // finest samples compared (on screen)
};

// Over `samples` random draws (a fixed seed: the same frame gives the same
// figure) inside the data's `extent`; of the refined mesh when given
// (edge-mark frames), else of the selection's MeshTopology meshes. Deciding
// which samples are covered reads the tiles that have nodata from the store
// when `read_tiles` allows (stills, benchmarks); interactive frames must not
// wait for I/O: their samples in such tiles are left out.
Result<MeasuredError> measure_screen_error(const View& view, TerrainModel& terrain,
                                           const Selection& selection, const geo::GeoBox& extent,
                                           int samples, const RefinedMesh* refined = nullptr,
                                           bool read_tiles = true);

// A point of the data: longitude, latitude (degrees) and its height there.
struct DataPoint {
  double lon = 0, lat = 0, height = 0;
};

// The same measure at given points (heights read by the caller, so another
// client's frame can be measured against the same data: bench/web): per
// point, the distance in pixels between the data point and the drawn mesh's
// point above its longitude and latitude, both projected; nullopt where the
// selection draws no quad there, the data point is off screen or its height
// is not finite (nodata).
Result<std::vector<std::optional<double>>> measure_screen_error_at(
    const View& view, TerrainModel& terrain, const Selection& selection,
    std::span<const DataPoint> points, const RefinedMesh* refined = nullptr);

}  // namespace relief::lod
