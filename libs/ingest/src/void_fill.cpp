#include "void_fill.h"

#include <gdal.h>

#include <algorithm>
#include <cmath>
#include <limits>

#include <fmt/format.h>

#include "gdal_env.h"

namespace relief::ingest {
namespace {

// Marks the nodata that is not a void: regions (8-connected) that reach the
// raster's edge and hold more than 1 % of its samples. A small region on the
// edge is a void cut by the tile boundary (SRTM tiles have no collar).
std::vector<uint8_t> outside(const std::vector<float>& v, int w, int h) {
  std::vector<uint8_t> out(v.size(), 0), seen(v.size(), 0);
  const size_t collar = v.size() / 100;
  std::vector<size_t> stack, region;
  auto visit = [&](size_t start) {
    if (seen[start] || !std::isnan(v[start])) return;
    region.clear();
    stack.assign(1, start);
    seen[start] = 1;
    while (!stack.empty()) {
      const size_t i = stack.back();
      stack.pop_back();
      region.push_back(i);
      const int x = static_cast<int>(i % w), y = static_cast<int>(i / w);
      for (int dy = -1; dy <= 1; ++dy) {
        for (int dx = -1; dx <= 1; ++dx) {
          const int nx = x + dx, ny = y + dy;
          if (nx < 0 || ny < 0 || nx >= w || ny >= h) continue;
          const size_t n = static_cast<size_t>(ny) * w + nx;
          if (!seen[n] && std::isnan(v[n])) {
            seen[n] = 1;
            stack.push_back(n);
          }
        }
      }
    }
    if (region.size() > collar) {
      for (size_t i : region) out[i] = 1;
    }
  };
  for (int x = 0; x < w; ++x)
    visit(static_cast<size_t>(x)), visit(static_cast<size_t>(h - 1) * w + x);
  for (int y = 0; y < h; ++y)
    visit(static_cast<size_t>(y) * w), visit(static_cast<size_t>(y) * w + w - 1);
  return out;
}

// One level of the pull-push pyramid: weighted means, weights clipped to 1.
struct Level {
  int w = 0, h = 0;
  std::vector<float> value, weight;
};

Level pull(const Level& fine) {
  Level c{(fine.w + 1) / 2, (fine.h + 1) / 2, {}, {}};
  c.value.assign(static_cast<size_t>(c.w) * c.h, 0.0f);
  c.weight.assign(c.value.size(), 0.0f);
  for (int y = 0; y < c.h; ++y) {
    for (int x = 0; x < c.w; ++x) {
      double sum = 0, weight = 0;
      for (int k = 0; k < 4; ++k) {
        const int fx = 2 * x + k % 2, fy = 2 * y + k / 2;
        if (fx >= fine.w || fy >= fine.h) continue;
        const size_t i = static_cast<size_t>(fy) * fine.w + fx;
        sum += double(fine.value[i]) * fine.weight[i];
        weight += fine.weight[i];
      }
      const size_t o = static_cast<size_t>(y) * c.w + x;
      if (weight > 0) c.value[o] = static_cast<float>(sum / weight);
      c.weight[o] = static_cast<float>(std::min(1.0, weight));
    }
  }
  return c;
}

// Bilinear value of `coarse` at the centre of fine sample (x, y).
float upsample(const Level& coarse, int x, int y) {
  const double cx = std::clamp((x + 0.5) / 2 - 0.5, 0.0, coarse.w - 1.0);
  const double cy = std::clamp((y + 0.5) / 2 - 0.5, 0.0, coarse.h - 1.0);
  const int x0 = static_cast<int>(cx), y0 = static_cast<int>(cy);
  const int x1 = std::min(x0 + 1, coarse.w - 1), y1 = std::min(y0 + 1, coarse.h - 1);
  const double fx = cx - x0, fy = cy - y0;
  auto at = [&](int xx, int yy) {
    return double(coarse.value[static_cast<size_t>(yy) * coarse.w + xx]);
  };
  const double top = at(x0, y0) + (at(x1, y0) - at(x0, y0)) * fx;
  const double bottom = at(x0, y1) + (at(x1, y1) - at(x0, y1)) * fx;
  return static_cast<float>(top + (bottom - top) * fy);
}

// Push: samples short of weight 1 blend in the coarser level's interpolation.
void push(Level& fine, const Level& coarse) {
  for (int y = 0; y < fine.h; ++y) {
    for (int x = 0; x < fine.w; ++x) {
      const size_t i = static_cast<size_t>(y) * fine.w + x;
      const float wgt = fine.weight[i];
      if (wgt >= 1) continue;
      fine.value[i] = wgt * fine.value[i] + (1 - wgt) * upsample(coarse, x, y);
      fine.weight[i] = 1;
    }
  }
}

}  // namespace

uint64_t fill_voids(std::vector<float>& values, int w, int h) {
  const std::vector<uint8_t> out = outside(values, w, h);
  uint64_t voids = 0;
  for (size_t i = 0; i < values.size(); ++i) voids += std::isnan(values[i]) && !out[i];
  if (voids == 0) return 0;
  std::vector<Level> levels(1);
  levels[0] = {w, h, values, std::vector<float>(values.size())};
  for (size_t i = 0; i < values.size(); ++i) {
    const bool valid = !std::isnan(values[i]);
    levels[0].weight[i] = valid ? 1.0f : 0.0f;
    if (!valid) levels[0].value[i] = 0;
  }
  while (levels.back().w > 1 || levels.back().h > 1) levels.push_back(pull(levels.back()));
  for (size_t l = levels.size() - 1; l-- > 0;) push(levels[l], levels[l + 1]);
  for (size_t i = 0; i < values.size(); ++i) {
    if (std::isnan(values[i]) && !out[i]) values[i] = levels[0].value[i];
  }
  return voids;
}

Result<std::optional<FilledSource>> fill_source_voids(const std::string& path,
                                                      const std::filesystem::path& copy,
                                                      bool always_copy) {
  const Dataset src = open_raster(path);
  if (!src) return fail(fmt::format("{}: {}", path, gdal_error("cannot open for reading")));
  const int w = GDALGetRasterXSize(src.get()), h = GDALGetRasterYSize(src.get());
  GDALRasterBandH band = GDALGetRasterBand(src.get(), 1);
  std::vector<float> values;
  if (auto err = read_padded(band, 0, 0, w, h, 0, values, path)) return fail(*err);
  for (float& v : values) {  // infinite samples are nodata (see build.cpp)
    if (!std::isfinite(v)) v = std::numeric_limits<float>::quiet_NaN();
  }
  const uint64_t filled = fill_voids(values, w, h);
  if (filled == 0 && !always_copy) return std::optional<FilledSource>{};

  std::error_code ec;
  std::filesystem::create_directories(copy.parent_path(), ec);
  const std::filesystem::path temp = copy.string() + ".tmp";
  const char* options[] = {"TILED=YES", "COMPRESS=ZSTD", nullptr};
  GDALDriverH gtiff = GDALGetDriverByName("GTiff");
  Dataset out{GDALCreateCopy(gtiff, temp.c_str(), src.get(), FALSE, const_cast<char**>(options),
                             nullptr, nullptr)};
  if (!out) return fail(fmt::format("{}: {}", temp.string(), gdal_error("cannot write")));
  // The band's nodata value stays for what is left (NaN reads back as nodata
  // only in float bands; filled samples are all finite).
  GDALRasterBandH out_band = GDALGetRasterBand(out.get(), 1);
  int has_nodata = 0;
  const double nodata = GDALGetRasterNoDataValue(out_band, &has_nodata);
  for (float& v : values) {
    if (std::isnan(v) && has_nodata) v = static_cast<float>(nodata);
  }
  if (GDALRasterIO(out_band, GF_Write, 0, 0, w, h, values.data(), w, h, GDT_Float32, 0, 0) !=
      CE_None) {
    return fail(fmt::format("{}: {}", temp.string(), gdal_error("cannot write")));
  }
  out.reset();  // flushes
  std::filesystem::rename(temp, copy, ec);
  if (ec) return fail(fmt::format("{}: {}", copy.string(), ec.message()));
  return std::optional<FilledSource>{FilledSource{copy, filled}};
}

}  // namespace relief::ingest
