#pragma once
// Independent references computed straight from GDAL for the ingest tests.
#include <string>
#include <vector>

namespace relief::testing {

// A whole raster band read through GDAL, with its geotransform and nodata.
struct SourceGrid {
  int width = 0, height = 0;
  double gt[6] = {};
  bool has_nodata = false;
  double nodata = 0;
  std::vector<double> values;
  double at(int i, int j) const { return values[static_cast<size_t>(j) * width + i]; }
  bool valid(int i, int j) const { return !(has_nodata && at(i, j) == nodata); }
};
SourceGrid read_source(const std::string& path, int band = 1);

// Bilinear value at (lon, lat) from the pixel centres of a north-up grid;
// false if any of the four supporting samples is nodata or outside.
bool bilinear(const SourceGrid& g, double lon, double lat, double& value);

// A raster in EPSG:4326 read back whole (all bands, band-sequential doubles).
struct Warped {
  int width = 0, height = 0, bands = 0;
  double gt[6] = {};
  std::vector<double> values;
  double at(int b, int i, int j) const {
    return values[(static_cast<size_t>(b) * height + j) * width + i];
  }
};
Warped read_warped(const std::string& path);
// gdalwarp `inputs` onto exactly the grid of `like` (same size and geotransform).
// error_threshold is gdalwarp's -et (source pixels; 0 = exact).
Warped gdalwarp_like(const std::vector<std::string>& inputs, const Warped& like,
                     const std::string& resampling, bool alpha, double error_threshold = 0.125,
                     const std::vector<std::string>& warp_options = {});
// gdalbuildvrt: mosaics inputs on their native grid (later inputs on top).
void build_vrt(const std::vector<std::string>& inputs, const std::string& path);

// Writes a Float32 or Int16 GeoTIFF in EPSG:4326 for synthetic cases.
void write_geotiff(const std::string& path, int width, int height, const double gt[6],
                   const std::vector<float>& values, const std::string& type = "Float32",
                   const std::string& srs = "EPSG:4326");

}  // namespace relief::testing
