// relief's own warp kernel for projected input gives GDAL's warper's result:
// the 2 x 2 bilinear when upsampling, GDAL's widened bilinear when
// downsampling, with the approximate transformer and with the exact one.
#include <gdal_utils.h>
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <stdexcept>

#include <fmt/format.h>

#include "../support/test_support.h"
#include "built_stores.h"
#include "gdal_env.h"
#include "projected_resample.h"

namespace relief::testing {
namespace {

// The real N42E001 tile reprojected to UTM 31N at `metres` per sample over a
// 15 km square (the Pyrenees, with nodata along the rotated footprint's edge).
std::string utm_input(const ScratchDir& dir, int metres) {
  ingest::init_gdal();
  const std::string out = (dir / fmt::format("utm{}.tif", metres)).string();
  const std::string src = "/vsizip/" + data("srtm/N42E001.hgt.zip") + "/N42E001.hgt";
  const std::string tr = std::to_string(metres);
  // The box straddles the western edge of the tile (lon 1.0), so part of it has no data.
  const char* argv[] = {"-q",    "-t_srs", "EPSG:32631", "-tr",    tr.c_str(), tr.c_str(),
                        "-te",   "330000", "4710000",    "345000", "4725000",  "-r",
                        "cubic", "-ot",    "Int16",      "-of",    "GTiff",    nullptr};
  GDALWarpAppOptions* options = GDALWarpAppOptionsNew(const_cast<char**>(argv), nullptr);
  GDALDatasetH in = GDALOpen(src.c_str(), GA_ReadOnly);
  if (!in) throw std::runtime_error("cannot open " + src);
  int usage_error = 0;
  GDALDatasetH ds = GDALWarp(out.c_str(), nullptr, 1, &in, options, &usage_error);
  GDALWarpAppOptionsFree(options);
  GDALClose(in);
  if (!ds || usage_error) throw std::runtime_error("gdalwarp to " + out + " failed");
  GDALClose(ds);
  return out;
}

const ScratchDir& inputs_dir() {
  static const ScratchDir dir("projected_inputs");
  return dir;
}

struct Difference {
  int64_t compared = 0, mask_mismatch = 0;
  double max_diff = 0;
};

// Sample by sample over every level: valid in both (compared), valid in one
// only (mask_mismatch), and the largest difference relative to the tolerance
// of a few ulps (source coordinates relative to the raster, not GDAL's window).
Difference compare_stores(const tiles::Store& a, const tiles::Store& b) {
  Difference d;
  EXPECT_EQ(a.manifest().max_level, b.manifest().max_level);
  for (int level = a.manifest().min_level; level <= a.manifest().max_level; ++level) {
    EXPECT_EQ(a.index(level).size(), b.index(level).size()) << "level " << level;
    for (const auto& e : a.index(level).entries()) {
      const tiles::Tile ta = must_read(a, e.key), tb = must_read(b, e.key);
      const auto va = ta.raster.f32(), vb = tb.raster.f32();
      for (size_t k = 0; k < va.size(); ++k) {
        if (std::isnan(va[k]) != std::isnan(vb[k])) {
          ++d.mask_mismatch;
        } else if (!std::isnan(va[k])) {
          const double ulps = std::max(1e-5, 2.5e-7 * std::abs(vb[k]));
          d.max_diff =
              std::max(d.max_diff, std::abs(va[k] - vb[k]) <= ulps ? 0.0 : std::abs(va[k] - vb[k]));
          ++d.compared;
        }
      }
    }
  }
  return d;
}

ingest::BuildOptions utm_options(int metres, int level, double warp_error) {
  ingest::BuildOptions o;
  o.inputs = {utm_input(inputs_dir(), metres)};
  o.kind = tiles::DatasetKind::Elevation;
  o.max_level = level;
  o.min_level = level - 1;
  o.warp_error = warp_error;
  return o;
}

// With every sample transformed exactly (--warp-error 0, gdalwarp -et 0) the
// kernel is GDAL's to a few ulps, the nodata mask included.
void expect_kernel_matches_gdal(const std::string& name, int metres, int level,
                                int64_t at_least = 40000) {
  ingest::BuildOptions o = utm_options(metres, level, 0);
  {  // the input takes relief's kernel unless --gdal-warp is given
    ingest::Dataset ds = ingest::open_raster(o.inputs.front());
    ASSERT_TRUE(ds);
    EXPECT_TRUE(ingest::ProjectedResampler::create(ds.get(), 0.125));
  }
  o.direct_resampling = false;
  const auto& gdal = built_store(name + "_gdal", o);
  o.direct_resampling = true;
  const auto& ours = built_store(name + "_relief", o);
  const Difference d = compare_stores(ours, gdal);
  EXPECT_GT(d.compared, at_least);
  EXPECT_EQ(d.mask_mismatch, 0);
  EXPECT_EQ(d.max_diff, 0);
}

// 90 m samples onto level 11 (38 m): upsampling, GDAL's 2 x 2 formula.
TEST(ProjectedResampling, UpsamplingMatchesGdalWarper) {
  expect_kernel_matches_gdal("utm90_l11", 90, 11);
}

// 30 m samples onto level 11 (scale 0.83), level 10 (0.42) and level 8
// (0.10): GDAL widens the bilinear filter to radius 2, 3 and 10.
TEST(ProjectedResampling, DownsamplingMatchesGdalWideBilinear) {
  expect_kernel_matches_gdal("utm30_l11", 30, 11);
  expect_kernel_matches_gdal("utm30_l10", 30, 10);
  expect_kernel_matches_gdal("utm30_l8", 30, 8, 2000);
}

// Far coarser tiles (level 6: scale 0.026, a filter radius of 39) are left to
// GDAL's warper, which works through them in chunks: the build succeeds and
// equals the one through GDALWarp.
TEST(ProjectedResampling, FarCoarserTilesGoToGdalsWarper) {
  expect_kernel_matches_gdal("utm30_l6", 30, 6, 100);
}

// Samples of `ours` at the finest level whose value lies outside the range of
// `ref`'s 3 x 3 neighbourhood around the same sample (the reprojection tests'
// "at most one sample of position error"), and the samples compared.
std::pair<int64_t, int64_t> outside_one_sample(const tiles::Store& ours, const tiles::Store& ref) {
  const int level = ours.manifest().max_level;
  int64_t outside = 0, compared = 0;
  for (const auto& e : ours.index(level).entries()) {
    const tiles::Tile ta = must_read(ours, e.key), tb = must_read(ref, e.key);
    const int w = ta.raster.width(), h = ta.raster.height();
    const auto va = ta.raster.f32(), vb = tb.raster.f32();
    for (int j = 1; j + 1 < h; ++j) {
      for (int i = 1; i + 1 < w; ++i) {
        const float v = va[static_cast<size_t>(j) * w + i];
        if (std::isnan(v)) continue;
        double lo = INFINITY, hi = -INFINITY;
        for (int k = 0; k < 9; ++k) {
          const float r = vb[static_cast<size_t>(j - 1 + k / 3) * w + i - 1 + k % 3];
          lo = std::min<double>(lo, r);
          hi = std::max<double>(hi, r);
        }
        if (std::isnan(lo) || std::isinf(lo)) continue;  // nodata in the neighbourhood
        ++compared;
        if (v < lo - 1e-3 || v > hi + 1e-3) ++outside;
      }
    }
  }
  return {outside, compared};
}

// With the approximate transformer (the default 0.125 source pixels) positions
// are interpolated along each tile row, where GDAL interpolates along the
// pieces it cuts a tile into when the tile reaches past the source's edge
// (every tile of this small input): values then differ from GDAL's by up to
// the error threshold's worth of position, and stay within one sample of the
// exact result as often as GDAL's do.
TEST(ProjectedResampling, ApproximateTransformErrsAsLittleAsGdals) {
  for (const int metres : {90, 30}) {
    SCOPED_TRACE(metres);
    const std::string name = fmt::format("utm{}_l11", metres);
    ingest::BuildOptions o = utm_options(metres, 11, 0);
    o.direct_resampling = false;
    const auto& exact = built_store(name + "_gdal", o);
    o.warp_error = 0.125;
    o.direct_resampling = true;
    const auto& ours = built_store(name + "_relief_approx", o);
    const auto [outside, compared] = outside_one_sample(ours, exact);
    o.direct_resampling = false;
    const auto& gdal = built_store(name + "_gdal_approx", o);
    const auto [g_out, g_cmp] = outside_one_sample(gdal, exact);
    // Near peaks and ridges a position error of a fraction of a sample takes a
    // value past its neighbours' range: GDAL's interpolation does that for
    // about 0.1 % of the samples, relief's for no more than twice as many.
    EXPECT_GT(compared, 100000);
    EXPECT_GT(g_cmp, 100000);
    EXPECT_LE(outside, 2 * g_out + 10);
    const Difference d = compare_stores(ours, exact);
    EXPECT_LE(d.mask_mismatch, d.compared / 1000);  // samples at the data's edge only
  }
}

}  // namespace
}  // namespace relief::testing
