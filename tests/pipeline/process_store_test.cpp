// `relief process STORE`: every level of the processed pyramid equals the
// operator run on the whole level at once (borders included, bit for bit),
// radii shrink with coarser levels, and bad input leaves nothing behind.
#include <gtest/gtest.h>

#include <cmath>
#include <cstring>

#include "../ingest/built_stores.h"
#include "../support/test_support.h"
#include "level_image.h"
#include "relief/pipeline/process_store.h"
#include "relief/process/operators.h"
#include "relief/tiles/verify.h"

namespace relief::testing {
namespace {

namespace fs = std::filesystem;

const tiles::Store& sar_store() {
  ingest::BuildOptions o;
  o.inputs = {data("sar/umbra_mount_yasur.tif")};
  o.kind = tiles::DatasetKind::Sar;
  return built_store("umbra", o);
}

tiles::Store process(const tiles::Store& in, const fs::path& out, const std::string& op,
                     const std::vector<std::string>& params) {
  ThreadExecutor ex(2);
  NullProgress progress;
  auto r = pipeline::process_store({in.root(), out, op, params}, ex, progress);
  if (!r) throw std::runtime_error(r.error().message);
  return std::move(*tiles::Store::open(out));
}

// Runs `op` over the whole level and compares every output tile, border
// included, with it.
void expect_level_matches_whole(const tiles::Store& in, const tiles::Store& out,
                                const std::string& op_name, const std::vector<std::string>& params,
                                int level) {
  SCOPED_TRACE(op_name + " level " + std::to_string(level));
  const process::OperatorSpec* op = process::find_operator(op_name);
  const int max_level = in.manifest().max_level;
  const auto p = process::scale_params(*op, *process::parse_params(*op, params),
                                       std::ldexp(1.0, max_level - level));
  const int m = process::margin_of(*op, p), b = in.manifest().border;
  const LevelImage whole_in = read_level(in, level, m + b);
  LevelImage whole_out = whole_in;
  whole_out.x0 += m, whole_out.y0 += m;
  whole_out.width -= 2 * m, whole_out.height -= 2 * m;
  whole_out.v.assign(static_cast<size_t>(whole_out.width) * whole_out.height, 0);
  const auto& s = in.manifest().stats;
  const process::GlobalStats g{s.min, s.max, s.mean, s.stddev};
  InlineExecutor ex;
  ASSERT_TRUE(process::run_operator(*op, p,
                                    {whole_in.v.data(), whole_in.width, whole_in.height,
                                     whole_in.width, whole_in.x0, whole_in.y0},
                                    {whole_out.v.data(), whole_out.width, whole_out.height,
                                     whole_out.width, whole_out.x0, whole_out.y0},
                                    ex, &g));
  const geo::TileGrid& grid = in.grid();
  ASSERT_EQ(out.index(level).size(), in.index(level).size());
  for (const auto& e : out.index(level).entries()) {
    auto tile = out.read_tile(e.key);
    ASSERT_TRUE(tile) << tile.error().message;
    const auto got = tile->raster.f32();
    for (int j = 0; j < tile->raster.height(); ++j) {
      for (int i = 0; i < tile->raster.width(); ++i) {
        const float want = whole_out.at(e.key.x * int64_t{grid.width()} + i - b,
                                        e.key.y * int64_t{grid.height()} + j - b);
        const float have = got[static_cast<size_t>(j) * tile->raster.width() + i];
        ASSERT_EQ(std::memcmp(&want, &have, sizeof(float)), 0)
            << e.key.to_string() << " sample " << i << "," << j << ": " << have << " vs " << want;
      }
    }
  }
}

TEST(ProcessStore, EveryLevelEqualsTheWholeLevelProcessedAtOnce) {
  const tiles::Store& in = sar_store();
  ScratchDir dir("process_store");
  const int max = in.manifest().max_level;
  const tiles::Store lee = process(in, dir / "lee", "lee", {"radius=4", "looks=2"});
  for (int level : {max, max - 1, max - 2}) {
    expect_level_matches_whole(in, lee, "lee", {"radius=4", "looks=2"}, level);
  }
  const tiles::Store es = process(in, dir / "es", "ext-schlick", {"max_radius=6", "d=0.8"});
  expect_level_matches_whole(in, es, "ext-schlick", {"max_radius=6", "d=0.8"}, max);
  expect_level_matches_whole(in, es, "ext-schlick", {"max_radius=6", "d=0.8"}, max - 1);
  EXPECT_EQ(es.manifest().units, "grey level");
  EXPECT_LE(es.manifest().stats.max, 1.0);
}

TEST(ProcessStore, MasksKeepTheirSizeOnTheGround) {
  const process::OperatorSpec* lee = process::find_operator("lee");
  const auto p = *process::parse_params(*lee, {"radius=8"});
  EXPECT_EQ(process::scale_params(*lee, p, 2).at("radius"), 4);
  EXPECT_EQ(process::scale_params(*lee, p, 4).at("radius"), 2);
  EXPECT_EQ(process::scale_params(*lee, p, 32).at("radius"), 0);
  EXPECT_EQ(process::scale_params(*lee, p, 2).at("looks"), p.at("looks"));
  const process::OperatorSpec* wavelet = process::find_operator("wavelet");
  const auto w = *process::parse_params(*wavelet, {"levels=3"});
  EXPECT_EQ(process::scale_params(*wavelet, w, 4).at("levels"), 1);
  // Coarse enough, the window is one sample: the level is copied unchanged.
  const tiles::Store& in = sar_store();
  ScratchDir dir("process_store_scale");
  const tiles::Store out = process(in, dir / "lee", "lee", {"radius=3"});
  const int coarse = in.manifest().max_level - 3;  // 3 / 8 rounds to 0
  for (const auto& e : in.index(coarse).entries()) {
    const auto a = must_read(in, e.key), b = must_read(out, e.key);
    ASSERT_EQ(std::memcmp(a.raster.bytes().data(), b.raster.bytes().data(), a.raster.byte_size()),
              0);
  }
}

TEST(ProcessStore, BadInputIsRefusedAndLeavesNothingBehind) {
  ScratchDir dir("process_store_bad");
  ThreadExecutor ex(2);
  NullProgress progress;
  auto expect_error = [&](pipeline::ProcessStoreOptions o, const std::string& needle) {
    auto r = pipeline::process_store(o, ex, progress);
    ASSERT_FALSE(r);
    EXPECT_NE(r.error().message.find(needle), std::string::npos) << r.error().message;
    EXPECT_FALSE(fs::exists(o.output)) << o.output;
    EXPECT_TRUE(temporary_files(dir.path()).empty());
    for (const auto& entry : fs::directory_iterator(dir.path())) {
      ADD_FAILURE() << "left behind: " << entry.path();
    }
  };
  const fs::path sar = sar_store().root(), dem = pyrenees_store().root();
  expect_error({dem, dir / "a", "lee", {}}, "expects SAR amplitude");
  expect_error({dem, dir / "b", "ext-schlick", {}}, "holds elevation");
  expect_error({sar, dir / "c", "sharpen", {}}, "unknown operator");
  expect_error({sar, dir / "d", "lee", {"radius=12"}}, "out of range");
  expect_error({dir / "missing", dir / "e", "mean", {}}, "missing");
  fs::create_directory(dir / "exists");
  auto r = pipeline::process_store({sar, dir / "exists", "mean", {}}, ex, progress);
  ASSERT_FALSE(r);
  EXPECT_NE(r.error().message.find("already exists"), std::string::npos);
  // Elevation may take the filters that are not SAR-specific.
  EXPECT_TRUE(pipeline::process_store({dem, dir / "median", "median", {"radius=2"}}, ex, progress));
  // With the geometric errors of the filtered heights: verify recomputes them.
  const tiles::VerifyReport report = tiles::verify_store(dir / "median", ex, progress);
  EXPECT_TRUE(report.ok()) << (report.ok() ? "" : report.problems.front());
}

}  // namespace
}  // namespace relief::testing
