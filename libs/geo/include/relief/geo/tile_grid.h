#pragma once
// Sample layout of quadtree tiles.
//
// A tile holds 2^(k+1) x 2^k interior samples (default k = 8: 512 x 256) plus an
// overlap border of b samples on every side (default 9). Samples are
// cell-centred ("pixel is area"): interior sample (i, j) of tile (l, x, y)
// covers the cell whose west/north edge is i*d, j*d degrees from the tile's
// west/north edge, and its value belongs to the cell centre
//   lon = west + (i + 0.5) * d,   lat = north - (j + 0.5) * d,
// with d = 360 / (2^l * 2^(k+1)) = 180 / (2^l * 2^k) degrees, so samples are
// square in degrees. Border samples use the same formula with i in [-b, 0) or
// [w, w + b). Cell-centring makes a parent sample exactly the average of the
// 2 x 2 child samples whose cells it covers.
#include <cstdint>

#include "relief/base/result.h"
#include "relief/geo/tile_key.h"

namespace relief::geo {

struct SampleIndex {
  TileKey tile;
  int i = 0;  // column within the tile interior, [0, width)
  int j = 0;  // row within the tile interior, [0, height)
};

class TileGrid {
 public:
  static constexpr int kDefaultLog2Height = 8;
  static constexpr int kDefaultBorder = 9;

  static Result<TileGrid> create(int log2_height = kDefaultLog2Height, int border = kDefaultBorder);
  TileGrid() : TileGrid(kDefaultLog2Height, kDefaultBorder) {}

  int log2_height() const { return log2_height_; }
  int width() const { return 2 << log2_height_; }   // interior samples per row
  int height() const { return 1 << log2_height_; }  // interior rows
  int border() const { return border_; }
  int padded_width() const { return width() + 2 * border_; }
  int padded_height() const { return height() + 2 * border_; }

  // Degrees between neighbouring samples at `level`.
  double sample_spacing(int level) const;
  // Finest level whose sample spacing is no coarser than `spacing_deg`.
  int level_for_spacing(double spacing_deg) const;

  double sample_lon(const TileKey& t, double i) const;
  double sample_lat(const TileKey& t, double j) const;
  // The interior sample whose cell contains (lon, lat); lon is wrapped into
  // [-180, 180), lat is clamped to the poles.
  SampleIndex locate(int level, double lon, double lat) const;
  // Continuous sample coordinates of (lon, lat) relative to tile t's interior
  // origin: (0, 0) is the centre of sample (0, 0).
  void to_sample_coords(const TileKey& t, double lon, double lat, double& fi, double& fj) const;

 private:
  TileGrid(int log2_height, int border) : log2_height_(log2_height), border_(border) {}
  int log2_height_;
  int border_;
};

}  // namespace relief::geo
