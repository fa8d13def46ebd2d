// Reprojected inputs land where gdalwarp puts them; lossless round trips are exact.
#include <gtest/gtest.h>

#include <cmath>

#include "../support/test_support.h"
#include "built_stores.h"
#include "gdal_reference.h"
#include "relief/ingest/export.h"

namespace relief::testing {
namespace {

Warped export_level(const tiles::Store& store, int level, const ScratchDir& dir,
                    std::optional<geo::GeoBox> bbox = std::nullopt) {
  ingest::ExportOptions o;
  o.store = store.root();
  o.level = level;
  o.bbox = bbox;
  o.output = dir / "export.tif";
  NullProgress progress;
  auto r = ingest::export_geotiff(o, progress);
  if (!r) throw std::runtime_error(r.error().message);
  return read_warped(o.output.string());
}

struct Agreement {
  int64_t compared = 0, within_one_sample = 0, near_exact = 0;
};

// "At most one sample of position error": every exported value lies within the
// range of the reference's 3 x 3 neighbourhood around the same sample.
Agreement compare_positions(const Warped& ours, const Warped& ref, int colour_bands, bool alpha,
                            double tolerance) {
  Agreement a;
  auto valid = [&](const Warped& w, int i, int j) {
    return alpha ? w.at(w.bands - 1, i, j) > 0 : !std::isnan(w.at(0, i, j));
  };
  for (int j = 1; j + 1 < ours.height; ++j) {
    for (int i = 1; i + 1 < ours.width; ++i) {
      if (!valid(ours, i, j)) continue;
      bool support = true;
      for (int k = 0; k < 9 && support; ++k) support = valid(ref, i - 1 + k % 3, j - 1 + k / 3);
      if (!support) continue;
      for (int b = 0; b < colour_bands; ++b) {
        double lo = INFINITY, hi = -INFINITY;
        for (int k = 0; k < 9; ++k) {
          lo = std::min(lo, ref.at(b, i - 1 + k % 3, j - 1 + k / 3));
          hi = std::max(hi, ref.at(b, i - 1 + k % 3, j - 1 + k / 3));
        }
        const double v = ours.at(b, i, j);
        ++a.compared;
        if (v >= lo - tolerance && v <= hi + tolerance) ++a.within_one_sample;
        if (std::abs(v - ref.at(b, i, j)) <= tolerance) ++a.near_exact;
      }
    }
  }
  return a;
}

TEST(Reprojection, UtmImageryLandsWhereGdalwarpPutsIt) {
  ingest::BuildOptions o;
  o.inputs = {data("imagery/RGB.byte.tif")};
  o.kind = tiles::DatasetKind::Imagery;
  o.codec = tiles::Codec::Png;
  o.warp_error = 0;  // exact transforms here and in the reference: positions must agree
  const auto& store = built_store("landsat", o);
  EXPECT_EQ(store.manifest().sources[0].crs, "EPSG:32618");
  ScratchDir dir("reproject_rgb");
  const int level = store.manifest().max_level;
  const Warped ours = export_level(store, level, dir);
  ASSERT_EQ(ours.bands, 4);
  const Warped ref = gdalwarp_like(o.inputs, ours, "cubic", true, 0);
  const Agreement a = compare_positions(ours, ref, 3, true, 1.0);
  EXPECT_GT(a.compared, 100000);
  EXPECT_EQ(a.within_one_sample, a.compared);
  EXPECT_GT(a.near_exact, a.compared * 99 / 100);
}

TEST(Reprojection, RotatedSarImageLandsWhereGdalwarpPutsIt) {
  ingest::BuildOptions o;
  o.inputs = {data("sar/umbra_mount_yasur.tif")};
  o.kind = tiles::DatasetKind::Sar;
  o.min_level = 14;
  o.warp_error = 0;
  const auto& store = built_store("umbra", o);
  // 0.59 m samples go to the next finer level: 17 (0.000005364 deg, about 0.6 m).
  ASSERT_EQ(store.manifest().max_level, 17);
  EXPECT_EQ(store.manifest().sources[0].crs, "EPSG:32759");
  EXPECT_EQ(store.manifest().units, "amplitude");
  ScratchDir dir("reproject_sar");
  const Warped ours = export_level(store, 17, dir);
  // Definitional difference: gdalwarp derives its resampling scale per
  // processing chunk from the bounding box of the source window; for this
  // image, rotated by ~104 degrees, that box is far larger than the chunk, so
  // gdalwarp widens (blurs) its bilinear kernel as if downsampling. relief fixes
  // the scale from the resolutions (XSCALE/YSCALE), i.e. plain bilinear here.
  // With the same fixed scale gdalwarp agrees sample for sample:
  const Warped same_scale =
      gdalwarp_like(o.inputs, ours, "bilinear", false, 0, {"XSCALE=1", "YSCALE=1"});
  const Agreement a = compare_positions(ours, same_scale, 1, false, 1e-3);
  EXPECT_GT(a.compared, 4000000);
  EXPECT_EQ(a.within_one_sample, a.compared);
  EXPECT_GT(a.near_exact, a.compared * 99 / 100);
  // And against gdalwarp's defaults the image is registered at the same place:
  // of all whole-sample offsets within +-2, zero matches best.
  const Warped defaults = gdalwarp_like(o.inputs, ours, "bilinear", false);
  double best = INFINITY;
  int best_dx = 99, best_dy = 99;
  for (int dy = -2; dy <= 2; ++dy) {
    for (int dx = -2; dx <= 2; ++dx) {
      double sum = 0;
      int64_t n = 0;
      for (int j = 2; j + 2 < ours.height; j += 3) {
        for (int i = 2; i + 2 < ours.width; i += 3) {
          const double x = ours.at(0, i, j), y = defaults.at(0, i + dx, j + dy);
          if (std::isnan(x) || std::isnan(y)) continue;
          sum += std::abs(x - y);
          ++n;
        }
      }
      if (n > 0 && sum / n < best) {
        best = sum / n;
        best_dx = dx;
        best_dy = dy;
      }
    }
  }
  EXPECT_EQ(best_dx, 0);
  EXPECT_EQ(best_dy, 0);
}

TEST(RoundTrip, LosslessExportEqualsGdalwarpOfTheInputs) {
  const auto& store = pyrenees_store();
  ScratchDir dir("roundtrip");
  const Warped ours = export_level(store, 10, dir);
  EXPECT_EQ(ours.gt[1], store.grid().sample_spacing(10));
  // The reference mosaics on the native grid first (gdalbuildvrt), as relief does,
  // then warps with gdalwarp's default transform error.
  build_vrt(pyrenees_inputs(), (dir / "mosaic.vrt").string());
  const Warped ref = gdalwarp_like({(dir / "mosaic.vrt").string()}, ours, "bilinear", false);
  ASSERT_EQ(ref.width, ours.width);
  double max_diff = 0;
  int64_t both = 0, mask_mismatch = 0;
  for (int j = 0; j < ours.height; ++j) {
    for (int i = 0; i < ours.width; ++i) {
      const double a = ours.at(0, i, j), b = ref.at(0, i, j);
      if (std::isnan(a) != std::isnan(b)) {
        ++mask_mismatch;
        continue;
      }
      if (std::isnan(a)) continue;
      max_diff = std::max(max_diff, std::abs(a - b));
      ++both;
    }
  }
  EXPECT_GT(both, 3000000);
  EXPECT_LE(max_diff, 1e-3);
  EXPECT_EQ(mask_mismatch, 0);
}

TEST(RoundTrip, ExportOfAWindowSnapsToTheSampleGrid) {
  const auto& store = pyrenees_store();
  ScratchDir dir("window");
  const Warped w = export_level(store, 10, dir, geo::GeoBox{1.25, 42.25, 1.5, 42.5});
  const double d = store.grid().sample_spacing(10);
  EXPECT_NEAR(w.gt[0], 1.25, d);
  EXPECT_NEAR(w.gt[3], 42.5, d);
  EXPECT_LE(w.gt[0], 1.25);
  EXPECT_NEAR(w.width * d, 0.25, 2 * d);
  auto v = store.sample(w.gt[0] + 0.5 * d, w.gt[3] - 0.5 * d, 10);
  ASSERT_TRUE(v && v->has_value());
  EXPECT_FLOAT_EQ(**v, static_cast<float>(w.at(0, 0, 0)));
}

}  // namespace
}  // namespace relief::testing
