#pragma once
// Where a quad's samples are in a data tile, and the terrain's height there
// as the renderer draws it. Below the terrain model (terrain_model.h), which
// hands out windows: what measures meshes against a tile's data (mesh_error.h,
// diamond_errors.h) needs only this.
#include <optional>

#include "relief/geo/tile_key.h"
#include "relief/tiles/raster.h"

namespace relief::lod {

// Where a quad's samples are in a data tile: interior sample coordinates
// (x right, y down, 0 at the tile's west/north edge) of quad-space (u, v) are
// (x0 + u * width, y0 + v * height).
struct DataWindow {
  std::optional<geo::TileKey> tile;  // nullopt: no data, height 0
  double x0 = 0, y0 = 0, width = 0, height = 0;
};

// Bilinear height at interior sample coordinates (x, y) of a bordered tile,
// exactly as the renderer's vertex shader computes it.
float bilinear_height(const tiles::Raster& bordered, int border, double x, double y);

}  // namespace relief::lod
