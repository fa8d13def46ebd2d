#include "direct_resample.h"

#include <ogr_srs_api.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <limits>
#include <mutex>
#include <span>
#include <vector>

#include <fmt/format.h>

namespace relief::ingest {
namespace {

bool is_wgs84_lon_lat(GDALDatasetH ds) {
  // The dataset's own SRS carries its data axis mapping (x = longitude for
  // GDAL rasters in the traditional GIS order).
  OGRSpatialReferenceH srs = GDALGetSpatialRef(ds);
  if (!srs) return false;
  OGRSpatialReferenceH wgs84 = OSRNewSpatialReference(nullptr);
  OSRImportFromEPSG(wgs84, 4326);
  const char* options[] = {"IGNORE_DATA_AXIS_TO_SRS_AXIS_MAPPING=YES", "CRITERION=EQUIVALENT",
                           nullptr};
  bool same = OSRIsSameEx(srs, wgs84, options) != 0;
  OSRDestroySpatialReference(wgs84);
  if (same) {
    int count = 0;
    const int* mapping = OSRGetDataAxisToSRSAxisMapping(srs, &count);
    same = count >= 2 && mapping[0] == 2 && mapping[1] == 1;  // data x = longitude
  }
  return same;
}

// Source column (or row) and the weight of that column for one destination
// coordinate, as GDAL's bilinear kernel derives them.
struct Tap {
  bool inside;   // GDAL only resamples points inside the source raster
  int pixel;     // the source pixel containing the point: it must be valid
  int index;     // first of the two pixels interpolated
  double ratio;  // weight of `index`
};

Tap tap_for(double src, int size) {
  const int pixel = static_cast<int>(src + 1e-10);
  const bool inside = src >= 0 && pixel < size;
  int index = static_cast<int>(std::floor(src - 0.5));
  double ratio = 1.5 - (src - index);
  if (index == -1) {  // GDAL clamps the first half pixel onto pixel 0
    index = 0;
    ratio = 1;
  }
  return {inside, pixel, index, ratio};
}

// The source window a tile's taps read, in source pixels (inclusive).
struct SourceWindow {
  int x0, x1, y0, y1;
};
struct KernelTaps {
  std::vector<Tap> cols, rows;
};

// Paints the window `src` (ww x wh samples from (x0, y0)) through the taps
// over `out`. T is the type the window was read as: float where it holds every
// value of the source's type exactly (half the bytes GDAL converts and this
// loop reads), double otherwise; the kernel computes in double either way.
template <class T>
void paint(const std::vector<T>& src, int ww, int wh, const SourceWindow& win,
           const KernelTaps& taps, bool has_nodata, double nodata, bool cover,
           std::span<float> out) {
  constexpr float kNoData = std::numeric_limits<float>::quiet_NaN();
  const int w = static_cast<int>(taps.cols.size()), h = static_cast<int>(taps.rows.size());
  const int x0 = win.x0, x1 = win.x1, y0 = win.y0, y1 = win.y1;
  const std::vector<Tap>& cols = taps.cols;
  const std::vector<Tap>& rows = taps.rows;
  // Validity of every window sample, once: a tap then costs one load. And
  // whether a whole window row is valid (most are), for the loop below.
  thread_local std::vector<uint8_t> valid, row_valid;
  valid.resize(src.size());
  row_valid.resize(static_cast<size_t>(wh));
  for (size_t r = 0; r < static_cast<size_t>(wh); ++r) {
    uint8_t all = 1;
    for (size_t k = r * static_cast<size_t>(ww); k < (r + 1) * static_cast<size_t>(ww); ++k) {
      valid[k] = !std::isnan(src[k]) && !(has_nodata && static_cast<double>(src[k]) == nodata);
      all &= valid[k];
    }
    row_valid[r] = all;
  }
  // Column offsets into a window row, -1 outside the window (= outside the raster).
  auto offset = [](int v, int lo, int hi) { return v < lo || v > hi ? -1 : v - lo; };
  struct ColumnTaps {
    int pixel, left, right;
    bool full;  // inside the raster, its own pixel and both taps in the window
  };
  thread_local std::vector<ColumnTaps> col_taps;
  col_taps.resize(static_cast<size_t>(w));
  for (int i = 0; i < w; ++i) {
    const Tap& t = cols[static_cast<size_t>(i)];
    ColumnTaps c{offset(t.pixel, x0, x1), offset(t.index, x0, x1), offset(t.index + 1, x0, x1),
                 false};
    c.full = t.inside && c.pixel >= 0 && c.left >= 0 && c.right >= 0;
    col_taps[static_cast<size_t>(i)] = c;
  }
  const size_t stride = static_cast<size_t>(ww);
  for (int j = 0; j < h; ++j) {
    const Tap ty = rows[static_cast<size_t>(j)];
    float* out_row = out.data() + static_cast<size_t>(j) * static_cast<size_t>(w);
    const int own_row = ty.inside ? offset(ty.pixel, y0, y1) : -1;
    if (own_row < 0) {
      if (cover) std::fill(out_row, out_row + w, kNoData);
      continue;
    }
    const int upper = offset(ty.index, y0, y1), lower = offset(ty.index + 1, y0, y1);
    const uint8_t* valid_own = valid.data() + static_cast<size_t>(own_row) * stride;
    // Rows outside the window have no valid samples: point them at nothing.
    const size_t up = upper < 0 ? 0 : static_cast<size_t>(upper) * stride;
    const size_t low = lower < 0 ? 0 : static_cast<size_t>(lower) * stride;
    // A sample left out: nodata when this source is the first painted.
    auto leave = [&](int i) {
      if (cover) out_row[i] = kNoData;
    };
    // Rows whose own, upper and lower window rows are all valid: every tap of
    // a full column is valid, and the sums below are the general loop's with
    // each test true (the same operations in the same order, so the same bits).
    const bool rows_valid = upper >= 0 && lower >= 0 && row_valid[static_cast<size_t>(own_row)] &&
                            row_valid[static_cast<size_t>(upper)] &&
                            row_valid[static_cast<size_t>(lower)];
    for (int i = 0; rows_valid && i < w; ++i) {
      const ColumnTaps c = col_taps[static_cast<size_t>(i)];
      if (!c.full) continue;  // left to the general loop
      const double rx = cols[static_cast<size_t>(i)].ratio;
      const double m_ul = rx * ty.ratio, m_ur = (1.0 - rx) * ty.ratio;
      const double m_ll = rx * (1.0 - ty.ratio), m_lr = (1.0 - rx) * (1.0 - ty.ratio);
      const size_t l = static_cast<size_t>(c.left), r = static_cast<size_t>(c.right);
      double divisor = 0, sum = 0;
      divisor += m_ul, sum += src[up + l] * m_ul;
      divisor += m_ur, sum += src[up + r] * m_ur;
      divisor += m_ll, sum += src[low + l] * m_ll;
      divisor += m_lr, sum += src[low + r] * m_lr;
      if (divisor < 0.00001) {
        leave(i);
        continue;
      }
      out_row[i] = static_cast<float>(divisor == 1.0 ? sum : sum / divisor);
    }
    for (int i = 0; i < w; ++i) {
      const Tap& tx = cols[static_cast<size_t>(i)];
      const ColumnTaps c = col_taps[static_cast<size_t>(i)];
      if (rows_valid && c.full) continue;  // done above
      if (!tx.inside || c.pixel < 0 || !valid_own[c.pixel]) {
        leave(i);
        continue;
      }
      auto tap = [&](int row_ok, size_t row, int col, double& v) {
        if (row_ok < 0 || col < 0 || !valid[row + static_cast<size_t>(col)]) return false;
        v = src[row + static_cast<size_t>(col)];
        return true;
      };
      double divisor = 0, sum = 0, v = 0;
      // Same order of accumulation as GDAL: upper left, upper right, lower left, lower right.
      const double m_ul = tx.ratio * ty.ratio, m_ur = (1.0 - tx.ratio) * ty.ratio;
      const double m_ll = tx.ratio * (1.0 - ty.ratio), m_lr = (1.0 - tx.ratio) * (1.0 - ty.ratio);
      if (tap(upper, up, c.left, v)) divisor += m_ul, sum += v * m_ul;
      if (tap(upper, up, c.right, v)) divisor += m_ur, sum += v * m_ur;
      if (tap(lower, low, c.left, v)) divisor += m_ll, sum += v * m_ll;
      if (tap(lower, low, c.right, v)) divisor += m_lr, sum += v * m_lr;
      if (divisor < 0.00001) {
        leave(i);
        continue;
      }
      out_row[i] = static_cast<float>(divisor == 1.0 ? sum : sum / divisor);
    }
  }
}

}  // namespace

std::optional<DirectResampler> DirectResampler::create(GDALDatasetH ds,
                                                       double destination_spacing) {
  DirectResampler r;
  if (GDALGetRasterCount(ds) != 1 || GDALGetGeoTransform(ds, r.gt_) != CE_None) return std::nullopt;
  if (r.gt_[2] != 0 || r.gt_[4] != 0 || r.gt_[1] <= 0 || r.gt_[5] >= 0) return std::nullopt;
  if (!is_wgs84_lon_lat(ds)) return std::nullopt;
  r.width_ = GDALGetRasterXSize(ds);
  r.height_ = GDALGetRasterYSize(ds);
  const double west = r.gt_[0], east = west + r.width_ * r.gt_[1];
  if (west < -180.0 - 1e-9 || east > 180.0 + 1e-9) return std::nullopt;
  // Upsampling (or equal spacing) only: GDAL's plain 2 x 2 kernel.
  if (std::min(r.gt_[1], -r.gt_[5]) < destination_spacing * (1 - 1e-12)) return std::nullopt;
  int has = 0;
  GDALRasterBandH band = GDALGetRasterBand(ds, 1);
  r.nodata_ = GDALGetRasterNoDataValue(band, &has);
  r.has_nodata_ = has != 0;
  const GDALDataType type = GDALGetRasterDataType(band);
  r.exact_in_float_ =
      type == GDT_Byte || type == GDT_Int16 || type == GDT_UInt16 || type == GDT_Float32;
  r.ds_ = ds;
  return r;
}

Status DirectResampler::resample(const geo::TileGrid& grid, const geo::TileKey& key,
                                 tiles::Raster& tile, bool cover) const {
  const int w = grid.width(), h = grid.height();
  std::vector<Tap> cols(static_cast<size_t>(w)), rows(static_cast<size_t>(h));
  for (int i = 0; i < w; ++i) {
    cols[i] = tap_for((grid.sample_lon(key, i) - gt_[0]) / gt_[1], width_);
  }
  for (int j = 0; j < h; ++j) {
    rows[j] = tap_for((grid.sample_lat(key, j) - gt_[3]) / gt_[5], height_);
  }
  // Source window needed by the taps, clipped to the raster.
  const int x0 = std::max(0, cols.front().index), x1 = std::min(width_ - 1, cols.back().index + 1);
  const int y0 = std::max(0, rows.front().index), y1 = std::min(height_ - 1, rows.back().index + 1);
  if (x0 > x1 || y0 > y1) {
    if (cover) std::ranges::fill(tile.f32(), std::numeric_limits<float>::quiet_NaN());
    return {};
  }
  const SourceWindow win{x0, x1, y0, y1};
  const int ww = x1 - x0 + 1, wh = y1 - y0 + 1;
  const size_t count = static_cast<size_t>(ww) * static_cast<size_t>(wh);
  // Reused per thread: no fresh pages per tile.
  thread_local std::vector<float> src32;
  thread_local std::vector<double> src64;
  void* data = nullptr;
  if (exact_in_float_) {
    src32.resize(count);
    data = src32.data();
  } else {
    src64.resize(count);
    data = src64.data();
  }
  {
    std::unique_lock<std::mutex> lock;
    if (read_mutex_) lock = std::unique_lock(*read_mutex_);
    if (GDALRasterIO(GDALGetRasterBand(ds_, 1), GF_Read, x0, y0, ww, wh, data, ww, wh,
                     exact_in_float_ ? GDT_Float32 : GDT_Float64, 0, 0) != CE_None) {
      return fail(fmt::format("tile {}: {}", key.to_string(), gdal_error("source read failed")));
    }
  }
  const KernelTaps taps{std::move(cols), std::move(rows)};
  if (exact_in_float_)
    paint(src32, ww, wh, win, taps, has_nodata_, nodata_, cover, tile.f32());
  else
    paint(src64, ww, wh, win, taps, has_nodata_, nodata_, cover, tile.f32());
  return {};
}

SharedDirectSources::SharedDirectSources(size_t groups) {
  for (size_t g = 0; g < groups; ++g) slots_.push_back(std::make_unique<Slot>());
}

const DirectResampler* SharedDirectSources::get(size_t g, double destination_spacing,
                                                const std::function<Result<Dataset>()>& open) {
  Slot& slot = *slots_.at(g);
  std::call_once(slot.once, [&] {
    auto ds = open();
    if (!ds || !*ds) return;  // the per-worker path reports the error
    slot.ds = std::move(*ds);
    slot.resampler = DirectResampler::create(slot.ds.get(), destination_spacing);
    if (slot.resampler) slot.resampler->serialise_reads(&slot.reads);
  });
  return slot.resampler ? &*slot.resampler : nullptr;
}

}  // namespace relief::ingest
