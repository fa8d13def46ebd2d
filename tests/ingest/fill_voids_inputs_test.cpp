// --fill-voids over whole input sets: every input reaches the store, whether
// it has voids or not. Each set is built twice, without and with the flag;
// the filled store must have every tile and every valid sample of the raw
// one, with equal values except next to a void of the inputs.
#include <gdal_utils.h>
#include <gtest/gtest.h>

#include <cmath>
#include <set>

#include <fmt/format.h>

#include "gdal_env.h"
#include "relief/ingest/build.h"
#include "relief/tiles/store.h"
#include "test_support.h"
#include "warp.h"

namespace relief::ingest {
namespace {

constexpr double kSrtmPerDegree = 1200;  // SRTM3 samples per degree

// Cuts the mosaic of `tiles` into a 3 x 3 grid of GeoTIFF pieces that share
// their edge rows and columns, as neighbouring SRTM tiles do.
std::vector<std::string> nine_pieces(const std::vector<std::string>& tiles,
                                     const std::filesystem::path& dir) {
  init_gdal();
  std::vector<const char*> names;
  for (const auto& t : tiles) names.push_back(t.c_str());
  int usage = 0;
  Dataset vrt(
      GDALBuildVRT("", static_cast<int>(names.size()), nullptr, names.data(), nullptr, &usage));
  EXPECT_TRUE(vrt);
  if (!vrt) return {};
  const int w = GDALGetRasterXSize(vrt.get()), h = GDALGetRasterYSize(vrt.get());
  std::vector<std::string> pieces;
  for (int py = 0; py < 3; ++py) {
    for (int px = 0; px < 3; ++px) {
      const int x0 = px * (w - 1) / 3, x1 = (px + 1) * (w - 1) / 3;
      const int y0 = py * (h - 1) / 3, y1 = (py + 1) * (h - 1) / 3;
      const std::vector<std::string> args = {"-srcwin",
                                             std::to_string(x0),
                                             std::to_string(y0),
                                             std::to_string(x1 - x0 + 1),
                                             std::to_string(y1 - y0 + 1),
                                             "-of",
                                             "GTiff",
                                             "-q"};
      std::vector<char*> argv;
      for (const auto& a : args) argv.push_back(const_cast<char*>(a.c_str()));
      argv.push_back(nullptr);
      GDALTranslateOptions* options = GDALTranslateOptionsNew(argv.data(), nullptr);
      const std::string piece = (dir / fmt::format("piece_{}{}.tif", py, px)).string();
      Dataset out(GDALTranslate(piece.c_str(), vrt.get(), options, &usage));
      GDALTranslateOptionsFree(options);
      EXPECT_TRUE(out) << piece;
      pieces.push_back(piece);
    }
  }
  return pieces;
}

// The voids of the inputs, as SRTM grid positions (column, row from 180 W, 90
// N); `samples` counts them per input (pieces share their edges).
std::set<std::pair<int64_t, int64_t>> void_positions(const std::vector<std::string>& inputs,
                                                     uint64_t& samples) {
  std::set<std::pair<int64_t, int64_t>> voids;
  samples = 0;
  for (const auto& path : inputs) {
    const Dataset ds = open_raster(path);
    EXPECT_TRUE(ds) << path;
    if (!ds) continue;
    const int w = GDALGetRasterXSize(ds.get()), h = GDALGetRasterYSize(ds.get());
    double gt[6];
    GDALGetGeoTransform(ds.get(), gt);
    std::vector<float> v;
    EXPECT_FALSE(read_padded(GDALGetRasterBand(ds.get(), 1), 0, 0, w, h, 0, v, path));
    for (int y = 0; y < h; ++y) {
      for (int x = 0; x < w; ++x) {
        if (!std::isnan(v[static_cast<size_t>(y) * w + x])) continue;
        ++samples;
        const double lon = gt[0] + (x + 0.5) * gt[1], lat = gt[3] + (y + 0.5) * gt[5];
        voids.insert({std::llround((lon + 180) * kSrtmPerDegree),
                      std::llround((90 - lat) * kSrtmPerDegree)});
      }
    }
  }
  return voids;
}

struct Comparison {
  uint64_t raw_valid = 0, newly_valid = 0, changed = 0, lost = 0, changed_away = 0;
};

// Compares the finest level sample by sample; checks every level's tile set
// and that every sample valid in `raw` is valid in `filled`.
Comparison compare(const tiles::Store& raw, const tiles::Store& filled,
                   const std::set<std::pair<int64_t, int64_t>>& voids) {
  Comparison c;
  const auto& m = raw.manifest();
  const int b = m.border;
  for (int level = m.min_level; level <= m.max_level; ++level) {
    EXPECT_EQ(raw.index(level).size(), filled.index(level).size()) << "level " << level;
    for (const tiles::IndexEntry& e : raw.index(level).entries()) {
      EXPECT_TRUE(filled.has_tile(e.key)) << e.key.to_string();
      if (!filled.has_tile(e.key)) continue;
      auto a = raw.read_tile(e.key), f = filled.read_tile(e.key);
      EXPECT_TRUE(a && f) << e.key.to_string();
      if (!a || !f) continue;
      const int w = raw.grid().width(), h = raw.grid().height(), pw = a->raster.width();
      for (int j = 0; j < h; ++j) {
        for (int i = 0; i < w; ++i) {
          const size_t k = static_cast<size_t>(j + b) * pw + static_cast<size_t>(i + b);
          const float va = a->raster.f32()[k], vf = f->raster.f32()[k];
          if (std::isnan(va)) {
            if (level == m.max_level && !std::isnan(vf)) ++c.newly_valid;
            continue;
          }
          if (std::isnan(vf)) ++c.lost;
          if (level != m.max_level) continue;
          ++c.raw_valid;
          if (va == vf) continue;
          ++c.changed;
          // Bilinear support: within two source samples of a void.
          const int64_t gx = std::llround((raw.grid().sample_lon(e.key, i) + 180) * kSrtmPerDegree);
          const int64_t gy = std::llround((90 - raw.grid().sample_lat(e.key, j)) * kSrtmPerDegree);
          bool near = false;
          for (int64_t dy = -2; dy <= 2 && !near; ++dy) {
            for (int64_t dx = -2; dx <= 2 && !near; ++dx) near = voids.contains({gx + dx, gy + dy});
          }
          if (!near) ++c.changed_away;
        }
      }
    }
  }
  return c;
}

struct InputSet {
  const char* name;
  std::vector<std::string> tiles;
  bool split;      // cut into 3 x 3 GeoTIFF pieces
  bool has_voids;  // some input has a void
};

void PrintTo(const InputSet& set, std::ostream* os) {
  *os << set.name;
}

class FillVoidsInputs : public ::testing::TestWithParam<InputSet> {};

TEST_P(FillVoidsInputs, EveryInputKeptAndValuesChangeOnlyAtVoids) {
  const InputSet& set = GetParam();
  testing::ScratchDir dir(std::string("fill_inputs_") + set.name);
  std::vector<std::string> inputs;
  for (const auto& t : set.tiles) inputs.push_back(testing::data("srtm/" + t + ".hgt.zip"));
  if (set.split) inputs = nine_pieces(inputs, dir.path());
  ASSERT_FALSE(inputs.empty());

  BuildOptions o;
  o.inputs = inputs;
  o.kind = tiles::DatasetKind::Elevation;
  o.tile_log2_height = 7;
  ThreadExecutor executor;
  NullProgress progress;
  o.output = dir / "raw";
  auto raw_report = build_store(o, executor, progress);
  ASSERT_TRUE(raw_report) << raw_report.error().message;
  o.output = dir / "filled";
  o.fill_voids = true;
  auto filled_report = build_store(o, executor, progress);
  ASSERT_TRUE(filled_report) << filled_report.error().message;
  auto raw = tiles::Store::open(dir / "raw");
  auto filled = tiles::Store::open(dir / "filled");
  ASSERT_TRUE(raw && filled);

  uint64_t void_samples = 0;
  const auto voids = void_positions(inputs, void_samples);
  EXPECT_EQ(!voids.empty(), set.has_voids);
  EXPECT_EQ(filled_report->voids_filled, void_samples);  // SRTM has no collar
  const Comparison c = compare(*raw, *filled, voids);
  EXPECT_GT(c.raw_valid, 0u);
  EXPECT_EQ(c.lost, 0u) << "samples valid without --fill-voids are nodata with it";
  EXPECT_EQ(c.changed_away, 0u) << "of " << c.changed << " changed samples";
  EXPECT_EQ(raw_report->tiles_written, filled_report->tiles_written);
  const tiles::SampleStats& rs = raw->manifest().stats;
  const tiles::SampleStats& fs = filled->manifest().stats;
  EXPECT_EQ(fs.valid_count, rs.valid_count + c.newly_valid);
  if (!set.has_voids) {
    EXPECT_EQ(c.changed, 0u);
    EXPECT_EQ(c.newly_valid, 0u);
    EXPECT_EQ(fs.min, rs.min);
    EXPECT_EQ(fs.max, rs.max);
    EXPECT_EQ(fs.mean, rs.mean);
  } else {
    EXPECT_GT(c.newly_valid, 0u);
    // A fill lies within the range of the data around it.
    EXPECT_GE(fs.min, rs.min - 1);
    EXPECT_LE(fs.max, rs.max + 1);
    EXPECT_NEAR(fs.mean, rs.mean, 0.01 * std::abs(rs.mean));
  }
}

INSTANTIATE_TEST_SUITE_P(
    Sets, FillVoidsInputs,
    ::testing::Values(InputSet{"with_voids", {"N41E001", "N42E001"}, false, true},
                      InputSet{"mixed", {"N55W004", "N55W003"}, false, true},
                      InputSet{"void_free_9", {"N55W003"}, true, false},
                      InputSet{"mixed_9", {"N55W004", "N55W003"}, true, true}),
    [](const auto& p) { return std::string(p.param.name); });

// A GeoTIFF next to an SRTM .hgt in one CRS differs in data type and colour
// interpretation, which GDAL's VRT builder answers by leaving the file out:
// both must reach the store.
TEST(FillVoidsInputs, DifferentFormatsInOneCrsAreAllKept) {
  testing::ScratchDir dir("mixed_formats");
  init_gdal();
  const std::string east = (dir / "east.tif").string();
  const char* argv[] = {"-ot", "Float32", "-q", nullptr};
  GDALTranslateOptions* options = GDALTranslateOptionsNew(const_cast<char**>(argv), nullptr);
  int usage = 0;
  {
    const Dataset src = open_raster(testing::data("srtm/N55W003.hgt.zip"));
    Dataset out(GDALTranslate(east.c_str(), src.get(), options, &usage));
    ASSERT_TRUE(out);
  }
  GDALTranslateOptionsFree(options);
  BuildOptions o;
  o.inputs = {testing::data("srtm/N55W004.hgt.zip"), east};
  o.kind = tiles::DatasetKind::Elevation;
  o.tile_log2_height = 7;
  o.max_level = 8;
  o.output = dir / "store";
  ThreadExecutor executor;
  NullProgress progress;
  auto report = build_store(o, executor, progress);
  ASSERT_TRUE(report) << report.error().message;
  // Level 8 tiles are 0.7 x 0.35 degrees: the east input alone covers some.
  auto store = tiles::Store::open(o.output);
  ASSERT_TRUE(store);
  uint64_t west_valid = 0, east_valid = 0;
  for (const tiles::IndexEntry& e : store->index(8).entries()) {
    (e.key.bounds().west >= -3 ? east_valid : west_valid) += e.valid_count;
  }
  EXPECT_GT(west_valid, 0u);
  EXPECT_GT(east_valid, 0u);
}

}  // namespace
}  // namespace relief::ingest
