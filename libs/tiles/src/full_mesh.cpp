#include "relief/tiles/full_mesh.h"

#include <algorithm>
#include <cassert>
#include <cmath>

#include "full_mesh_cell.h"

namespace relief::tiles {
namespace {

// The cell holding x: the last cell for x == its upper bound.
int cell_of(double x, int interior) {
  return std::min(static_cast<int>(std::floor(x)), interior - 1);
}

}  // namespace

// lod::TerrainModel::bilinear at x = cx: tx = cx - 0.5 + border, so fx = 0.5
// and its first sample is cx - 1 + border; the same clamping and the same
// float expressions, hence the same bits.
float corner_height(const Raster& r, int border, int cx, int cy) {
  assert(r.type() == SampleType::Float32);
  const float f = 0.5f;
  const int w = r.width(), h = r.height();
  const auto v = r.f32();
  const int x0 = std::clamp(cx - 1 + border, 0, w - 1), x1 = std::min(x0 + 1, w - 1);
  const int y0 = std::clamp(cy - 1 + border, 0, h - 1), y1 = std::min(y0 + 1, h - 1);
  auto at = [&](int xx, int yy) {
    return v[static_cast<size_t>(yy) * static_cast<size_t>(w) + static_cast<size_t>(xx)];
  };
  const float top = at(x0, y0) + (at(x1, y0) - at(x0, y0)) * f;
  const float bottom = at(x0, y1) + (at(x1, y1) - at(x0, y1)) * f;
  return top + (bottom - top) * f;
}

MeshCell mesh_cell(const Raster& r, int border, int i, int j) {
  const auto v = r.f32();
  const float centre = v[static_cast<size_t>(j + border) * static_cast<size_t>(r.width()) +
                         static_cast<size_t>(i + border)];
  return make_cell(centre, corner_height(r, border, i, j), corner_height(r, border, i + 1, j),
                   corner_height(r, border, i, j + 1), corner_height(r, border, i + 1, j + 1),
                   stencil_inside(r, border, i, j));
}

double full_mesh_height(const Raster& bordered, int border, double x, double y) {
  const int i = cell_of(x, bordered.width() - 2 * border);
  const int j = cell_of(y, bordered.height() - 2 * border);
  return cell_height(mesh_cell(bordered, border, i, j), x - i, y - j);
}

bool full_mesh_stencil_valid(const Raster& bordered, int border, double x, double y) {
  const int i = cell_of(x, bordered.width() - 2 * border);
  const int j = cell_of(y, bordered.height() - 2 * border);
  return mesh_cell(bordered, border, i, j).valid;
}

}  // namespace relief::tiles
