#include "projected_resample.h"

#include <gdal_alg.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <vector>

#include <fmt/format.h>

namespace relief::ingest {
namespace {

// The source window read for one tile, in Float64 like GDAL's general case.
struct Window {
  int x0 = 0, y0 = 0, w = 0, h = 0;
  std::vector<double> values;
  bool has_nodata = false;
  double nodata = 0;
  // Valid and inside the window (the window holds every sample a kernel reaches).
  bool get(int x, int y, double& v) const {
    if (x < x0 || y < y0 || x >= x0 + w || y >= y0 + h) return false;
    v = values[static_cast<size_t>(y - y0) * static_cast<size_t>(w) + static_cast<size_t>(x - x0)];
    return !std::isnan(v);  // nodata was made NaN when read
  }
};

// GDAL's GWKBilinearResample4Sample: the plain 2 x 2 kernel.
bool bilinear4(const Window& win, double sx, double sy, double& out) {
  int ix = static_cast<int>(std::floor(sx - 0.5)), iy = static_cast<int>(std::floor(sy - 0.5));
  double rx = 1.5 - (sx - ix), ry = 1.5 - (sy - iy);
  if (ix == -1) {  // GDAL clamps the first half pixel onto pixel 0
    ix = 0;
    rx = 1;
  }
  if (iy == -1) {
    iy = 0;
    ry = 1;
  }
  double divisor = 0, sum = 0, v = 0;
  // Same order of accumulation as GDAL: upper left, upper right, lower left, lower right.
  const double m_ul = rx * ry, m_ur = (1.0 - rx) * ry;
  const double m_ll = rx * (1.0 - ry), m_lr = (1.0 - rx) * (1.0 - ry);
  if (win.get(ix, iy, v)) divisor += m_ul, sum += v * m_ul;
  if (win.get(ix + 1, iy, v)) divisor += m_ur, sum += v * m_ur;
  if (win.get(ix, iy + 1, v)) divisor += m_ll, sum += v * m_ll;
  if (win.get(ix + 1, iy + 1, v)) divisor += m_lr, sum += v * m_lr;
  if (divisor < 0.00001) return false;
  out = divisor == 1.0 ? sum : sum / divisor;
  return true;
}

// GDAL's GWKBilinear (1 - |x| up to 1, else 0), without a branch to mispredict.
double triangle(double x) {
  return std::max(0.0, 1.0 - std::fabs(x));
}

// GDAL's GWKResample with its bilinear filter at scale < 1: a (2 r + 1)^2
// window of triangle weights stretched by 1 / scale, invalid samples left out
// and the rest renormalised; the same loop bounds, clipping and order of
// accumulation (rows of weighted sums, then the sum of rows). Taps of zero
// weight add exact zeros to GDAL's sums, so they are skipped when the window
// holds no infinite value (inf * 0 would make GDAL's sum NaN).
bool bilinear_wide(const Window& win, bool finite, int width, int height, double sx, double sy,
                   double scale, int radius, double& out) {
  const int ix = static_cast<int>(std::floor(sx - 0.5));
  const int iy = static_cast<int>(std::floor(sy - 0.5));
  const double dx = sx - 0.5 - ix, dy = sy - 0.5 - iy;
  int j_min = -radius, j_max = radius;
  if (iy + j_min < 0) j_min = -iy;
  if (iy + j_max >= height) j_max = height - iy - 1;
  int i_min = -radius, i_max = radius;
  if (ix + i_min < 0) i_min = -ix;
  if (ix + i_max >= width) i_max = width - ix - 1;
  double weights_x[64], weights_y[64];  // radius <= 31: scale >= 1/31 (checked by the caller)
  for (int i = i_min; i <= i_max; ++i) weights_x[i - i_min] = triangle((i - dx) * scale);
  for (int j = j_min; j <= j_max; ++j) weights_y[j - j_min] = triangle((j - dy) * scale);
  int i_lo = i_min, i_hi = i_max, j_lo = j_min, j_hi = j_max;
  if (finite) {
    while (i_lo <= i_hi && weights_x[i_lo - i_min] == 0) ++i_lo;
    while (i_hi >= i_lo && weights_x[i_hi - i_min] == 0) --i_hi;
    while (j_lo <= j_hi && weights_y[j_lo - j_min] == 0) ++j_lo;
    while (j_hi >= j_lo && weights_y[j_hi - j_min] == 0) --j_hi;
  }
  // Inside the raster, hence inside the window, which holds every tap.
  const size_t stride = static_cast<size_t>(win.w);
  double acc = 0, acc_weight = 0;
  for (int j = j_lo; j <= j_hi; ++j) {
    const double w1 = weights_y[j - j_min];
    const double* row_values = win.values.data() + static_cast<size_t>(iy + j - win.y0) * stride +
                               static_cast<ptrdiff_t>(ix - win.x0);
    double row = 0, row_weight = 0;
    for (int i = i_lo; i <= i_hi; ++i) {
      const double v = row_values[i];
      if (std::isnan(v)) continue;  // nodata was made NaN
      const double w2 = weights_x[i - i_min];
      row += v * w2;
      row_weight += w2;
    }
    acc += row * w1;
    acc_weight += row_weight * w1;
  }
  if (acc_weight < 0.000001) return false;
  out = (acc_weight < 0.99999 || acc_weight > 1.00001) ? acc / acc_weight : acc;
  return true;
}

}  // namespace

void ProjectedResampler::TransformerDeleter::operator()(void* t) const {
  if (t) GDALDestroyTransformer(t);
}

std::optional<ProjectedResampler> ProjectedResampler::create(GDALDatasetH ds,
                                                             double error_threshold) {
  ProjectedResampler r;
  double gt[6];
  if (GDALGetRasterCount(ds) != 1 || GDALGetGeoTransform(ds, gt) != CE_None) return std::nullopt;
  if (!GDALGetSpatialRef(ds)) return std::nullopt;
  // The tile's stand-in, as the destination GDAL's warper is given.
  r.dst_ = Dataset(GDALCreate(GDALGetDriverByName("MEM"), "", 1, 1, 1, GDT_Float32, nullptr));
  if (!r.dst_) return std::nullopt;
  const double unit[6] = {0, 1, 0, 0, 0, -1};
  GDALSetGeoTransform(r.dst_.get(), const_cast<double*>(unit));
  GDALSetProjection(r.dst_.get(), kWgs84Wkt);
  r.exact_.reset(GDALCreateGenImgProjTransformer2(ds, r.dst_.get(), nullptr));
  if (!r.exact_) return std::nullopt;
  if (error_threshold > 0) {
    r.approx_.reset(
        GDALCreateApproxTransformer(GDALGenImgProjTransform, r.exact_.get(), error_threshold));
    if (!r.approx_) return std::nullopt;
  }
  r.ds_ = ds;
  r.width_ = GDALGetRasterXSize(ds);
  r.height_ = GDALGetRasterYSize(ds);
  int has = 0;
  r.nodata_ = GDALGetRasterNoDataValue(GDALGetRasterBand(ds, 1), &has);
  r.has_nodata_ = has != 0;
  return r;
}

Result<bool> ProjectedResampler::resample(const geo::TileGrid& grid, const geo::TileKey& key,
                                          double scale, tiles::Raster& tile) {
  const int w = grid.width(), h = grid.height();
  const geo::GeoBox b = key.bounds();
  const double d = grid.sample_spacing(key.level);
  double gt[6] = {b.west, d, 0, b.north, 0, -d};
  GDALSetGenImgProjTransformerDstGeoTransform(exact_.get(), gt);
  // Source positions of the sample centres, row by row as GDAL's kernel asks.
  const size_t n = static_cast<size_t>(w) * static_cast<size_t>(h);
  thread_local std::vector<double> xs, ys, zs;
  thread_local std::vector<int> ok;
  xs.resize(n);
  ys.resize(n);
  zs.assign(static_cast<size_t>(w), 0.0);
  ok.resize(n);
  double min_x = INFINITY, min_y = INFINITY, max_x = -INFINITY, max_y = -INFINITY;
  for (int j = 0; j < h; ++j) {
    const size_t row = static_cast<size_t>(j) * static_cast<size_t>(w);
    double* x = xs.data() + row;
    double* y = ys.data() + row;
    for (int i = 0; i < w; ++i) {
      x[i] = i + 0.5;
      y[i] = j + 0.5;
      zs[static_cast<size_t>(i)] = 0.0;
    }
    int* good = ok.data() + row;
    if (approx_)
      GDALApproxTransform(approx_.get(), TRUE, w, x, y, zs.data(), good);
    else
      GDALGenImgProjTransform(exact_.get(), TRUE, w, x, y, zs.data(), good);
    for (int i = 0; i < w; ++i) {
      if (!good[i] || std::isnan(x[i]) || std::isnan(y[i])) {
        good[i] = 0;
        continue;
      }
      min_x = std::min(min_x, x[i]);
      max_x = std::max(max_x, x[i]);
      min_y = std::min(min_y, y[i]);
      max_y = std::max(max_y, y[i]);
    }
  }
  if (!(min_x <= max_x)) return true;  // nothing lands anywhere
  const bool four = scale >= 0.95;
  const int radius = four ? 1 : static_cast<int>(std::ceil(1.0 / scale));
  if (radius > 31) return false;  // beyond the weight buffers: GDAL's warper
  // Every sample any kernel reaches, clipped to the raster.
  auto clip = [](double v, int size) {
    return static_cast<int>(std::clamp(v, -1.0, static_cast<double>(size)));
  };
  Window win;
  win.x0 = std::max(0, clip(std::floor(min_x - 0.5), width_) - radius);
  win.y0 = std::max(0, clip(std::floor(min_y - 0.5), height_) - radius);
  const int x1 = std::min(width_ - 1, clip(std::floor(max_x - 0.5), width_) + radius + 1);
  const int y1 = std::min(height_ - 1, clip(std::floor(max_y - 0.5), height_) + radius + 1);
  if (win.x0 > x1 || win.y0 > y1) return true;
  win.w = x1 - win.x0 + 1;
  win.h = y1 - win.y0 + 1;
  if (int64_t{win.w} * win.h > kMaxWindowSamples) return false;
  win.has_nodata = has_nodata_;
  win.nodata = nodata_;
  thread_local std::vector<double> buffer;  // reused: no fresh pages per tile
  buffer.resize(static_cast<size_t>(win.w) * static_cast<size_t>(win.h));
  if (GDALRasterIO(GDALGetRasterBand(ds_, 1), GF_Read, win.x0, win.y0, win.w, win.h, buffer.data(),
                   win.w, win.h, GDT_Float64, 0, 0) != CE_None) {
    return fail(fmt::format("tile {}: {}", key.to_string(), gdal_error("source read failed")));
  }
  win.values.swap(buffer);
  // One pass over the window: nodata becomes NaN (one test per tap), and
  // whether any value is infinite.
  bool finite = true;
  for (double& v : win.values) {
    if (win.has_nodata && v == win.nodata) v = std::numeric_limits<double>::quiet_NaN();
    finite = finite && !std::isinf(v);
  }
  auto out = tile.f32();
  for (size_t k = 0; k < n; ++k) {
    if (!ok[k]) continue;
    const double sx = xs[k], sy = ys[k];
    // GDAL resamples only points inside the raster whose own pixel is valid.
    if (sx < 0 || sy < 0) continue;
    const int px = static_cast<int>(sx + 1e-10), py = static_cast<int>(sy + 1e-10);
    double v = 0;
    if (px >= width_ || py >= height_ || !win.get(px, py, v)) continue;
    const bool valid = four ? bilinear4(win, sx, sy, v)
                            : bilinear_wide(win, finite, width_, height_, sx, sy, scale, radius, v);
    if (valid) out[k] = static_cast<float>(v);
  }
  win.values.swap(buffer);
  return true;
}

}  // namespace relief::ingest
