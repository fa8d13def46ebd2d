#pragma once
// The exact error of a quad's mesh against the data samples it covers: a pure
// function of the tile, so the loader's threads can measure it as a finest
// tile arrives (terrain_model.cpp) instead of the render thread.
#include "relief/lod/data_window.h"
#include "relief/lod/mesh_topology.h"
#include "relief/tiles/raster.h"

namespace relief::lod {

// max |mesh - data| over the samples of bordered tile `t` inside window `w`,
// for the plain and the split border triangles, the mesh's vertices taking
// the tile's bilinear heights (as the vertex shader does). With `full_mesh`,
// against the tile's full mesh instead (every sample a vertex, sample corners
// at their bilinear heights), whose vertices are the samples and the corners:
// the mesh is a coarsening of it, so their largest difference is at those.
double mesh_sample_error(const MeshTopology& mesh, const tiles::Raster& t, int border,
                         const DataWindow& w, bool full_mesh = false);

}  // namespace relief::lod
