#pragma once
// One cell of the full mesh (relief/tiles/full_mesh.h): what full_mesh_height
// evaluates, shared with the geometric error's batch loop so that both give
// the same bits. Each of the cell's 4 triangles is the plane
// h = (a + c v) + b u over (u, v) in [0, 1]^2, evaluated in that order.
#include <algorithm>
#include <cmath>

#include "relief/tiles/raster.h"

namespace relief::tiles {

struct MeshCell {
  // Triangles: 0 on the edge v = 0, 1 on u = 1, 2 on v = 1, 3 on u = 0.
  double a[4] = {}, b[4] = {}, c[4] = {};
  double lo = 0, hi = 0;  // the lowest and highest of its 5 vertices
  bool valid = false;     // every sample of the 3 x 3 stencil present
};

// The bilinear height at the interior corner (cx, cy), as the renderer
// computes it (lod::TerrainModel::bilinear at an integer point).
float corner_height(const Raster& bordered, int border, int cx, int cy);

// Whether the 3 x 3 stencil of cell (i, j) lies inside the raster.
inline bool stencil_inside(const Raster& bordered, int border, int i, int j) {
  const int bx = i + border, by = j + border;
  return bx >= 1 && by >= 1 && bx + 1 < bordered.width() && by + 1 < bordered.height();
}

// A cell from its centre sample and corner heights (h00, h10, h01, h11). The
// 4 corners average the whole 3 x 3 stencil, so the stencil holds no nodata
// exactly when neither they nor the centre are NaN (samples are finite).
// Always inlined: the geometric error makes one per ancestor cell over every
// finest tile (20 million for the Himalaya block), and a call returning the
// cell through memory cost as much as all the distances it serves.
[[gnu::always_inline]] inline MeshCell make_cell(float centre, float c00, float c10, float c01,
                                                 float c11, bool inside) {
  MeshCell cell;
  const double c = centre, h00 = c00, h10 = c10, h01 = c01, h11 = c11;
  cell.valid = inside && !std::isnan(c) && !std::isnan(h00) && !std::isnan(h10) &&
               !std::isnan(h01) && !std::isnan(h11);
  cell.lo = std::min({c, h00, h10, h01, h11});
  cell.hi = std::max({c, h00, h10, h01, h11});
  // The centre (1/2, 1/2) has height c; each triangle interpolates it with
  // the two corners of its edge.
  const double planes[4][3] = {
      {h00, h10 - h00, 2 * c - h00 - h10},          // edge v = 0: (0,0), (1,0)
      {2 * c - h11, h10 + h11 - 2 * c, h11 - h10},  // edge u = 1: (1,0), (1,1)
      {2 * c - h11, h11 - h01, h01 + h11 - 2 * c},  // edge v = 1: (0,1), (1,1)
      {h00, 2 * c - h00 - h01, h01 - h00},          // edge u = 0: (0,0), (0,1)
  };
  for (int t = 0; t < 4; ++t) {
    cell.a[t] = planes[t][0];
    cell.b[t] = planes[t][1];
    cell.c[t] = planes[t][2];
  }
  return cell;
}

// Cell (i, j) of the interior.
MeshCell mesh_cell(const Raster& bordered, int border, int i, int j);

// The triangle of the cell holding (u, v); on a diagonal, either triangle
// gives the same height (up to rounding), this picks one deterministically.
inline int cell_triangle(double u, double v) {
  if (v <= u) return u + v <= 1 ? 0 : 1;
  return u + v >= 1 ? 2 : 3;
}

// The height at (u, v) within the cell.
inline double cell_height(const MeshCell& cell, double u, double v) {
  const int t = cell_triangle(u, v);
  const double row = cell.a[t] + cell.c[t] * v;
  return row + cell.b[t] * u;
}

}  // namespace relief::tiles
