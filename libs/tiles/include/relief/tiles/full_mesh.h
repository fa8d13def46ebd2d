#pragma once
// The full mesh of one level's elevation data, the surface a tile's geometric
// error is measured from (docs/store-format.md, "Geometric error"): every
// sample is a vertex at its cell's centre, each cell is cut by its diagonals
// into 4 triangles, and the cell's corners have the renderer's bilinear height
// (the mean of the 4 samples around the corner, with the float arithmetic of
// lod::TerrainModel::bilinear, so the heights are bit-identical).
//
// Coordinates are a tile's interior coordinates: sample i's centre is at
// x = i + 0.5, the interior spans [0, width] x [0, height]. The raster is a
// bordered Float32 tile (border samples from the neighbours).
#include "relief/tiles/raster.h"

namespace relief::tiles {

// The full mesh's height at (x, y), 0 <= x <= width, 0 <= y <= height: the
// linear interpolation within the triangle holding the point. Nodata (NaN)
// samples propagate; decode them as the renderer does, or check the stencil.
double full_mesh_height(const Raster& bordered, int border, double x, double y);

// Whether the mesh at (x, y) represents data: the 3 x 3 samples around the
// cell holding the point (its centre sample and those its 4 corners average)
// are all inside the bordered raster and valid (not NaN).
bool full_mesh_stencil_valid(const Raster& bordered, int border, double x, double y);

}  // namespace relief::tiles
