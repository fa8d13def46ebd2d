// `relief process` on the real Umbra SAR image, against OTB's Despeckle, and
// its bad-input handling.
#include <gtest/gtest.h>

#include <cmath>

#include "../ingest/gdal_reference.h"
#include "test_support.h"

namespace relief::testing {
namespace {
namespace fs = std::filesystem;

struct Case {
  const char* otb_name;
  const char* relief_op;
  std::vector<std::string> relief_params;
  std::vector<std::string> otb_params;
};

// Definitions match where windows are complete: OTB replicates the edge
// samples (zero-flux Neumann) while relief leaves samples beyond the data out
// of the window, so the outermost `radius` rows and columns differ by design.
TEST(ProcessVsOtb, DespeckleFiltersAgreeAwayFromTheEdges) {
  ScratchDir dir("process_otb");
  const std::string crop = (dir / "crop.tif").string();
  ASSERT_EQ(std::system(("gdal_translate -q -srcwin 600 700 300 260 " +
                         data("sar/umbra_mount_yasur.tif") + " " + crop)
                            .c_str()),
            0);
  const std::vector<Case> cases = {
      {"lee", "lee", {"looks=2"}, {"-filter.lee.nblooks", "2"}},
      {"kuan", "kuan", {"looks=2"}, {"-filter.kuan.nblooks", "2"}},
      {"gammamap", "gamma-map", {"looks=2"}, {"-filter.gammamap.nblooks", "2"}},
      {"frost", "frost", {"deramp=0.2"}, {"-filter.frost.deramp", "0.2"}},
  };
  for (const auto& c : cases) {
    for (int radius : {1, 3}) {
      SCOPED_TRACE(std::string(c.otb_name) + " radius " + std::to_string(radius));
      const std::string ours = (dir / (std::string(c.otb_name) + "_relief.tif")).string();
      const std::string theirs = (dir / (std::string(c.otb_name) + "_otb.tif")).string();
      std::vector<std::string> args = {
          "process", crop,        "-o",      ours,
          "--op",    c.relief_op, "--param", "radius=" + std::to_string(radius),
          "-q"};
      for (const auto& p : c.relief_params) args.insert(args.end(), {"--param", p});
      auto r = run_relief(args);
      ASSERT_EQ(r.exit_code, 0) << r.err;
      std::string otb = "otbcli_Despeckle -in " + crop + " -out " + theirs + " float -filter " +
                        c.otb_name + " -filter." + c.otb_name + ".rad " + std::to_string(radius);
      for (const auto& p : c.otb_params) otb += " " + p;
      ASSERT_EQ(std::system((otb + " >/dev/null 2>&1").c_str()), 0) << otb;
      const Warped a = read_warped(ours), b = read_warped(theirs);
      ASSERT_EQ(a.width, b.width);
      double worst = 0;
      for (int y = radius; y < a.height - radius; ++y) {
        for (int x = radius; x < a.width - radius; ++x) {
          const double va = a.at(0, x, y), vb = b.at(0, x, y);
          worst = std::max(worst, std::abs(va - vb) / std::max(1.0, std::abs(vb)));
        }
      }
      EXPECT_LE(worst, 1e-4);
    }
  }
}

TEST(Process, BadInputsAreOneLineErrors) {
  ScratchDir dir("process_bad");
  const std::string out = (dir / "o.tif").string();
  const std::string sar = data("sar/umbra_mount_yasur.tif");
  auto expect_error = [&](std::vector<std::string> args, const std::string& needle) {
    auto r = run_relief(args);
    EXPECT_TRUE(is_one_line_error(r, needle)) << needle << ": " << r.err;
    EXPECT_FALSE(fs::exists(out));
  };
  expect_error({"process", sar, "-o", out, "--op", "sharpen"}, "unknown operator 'sharpen'");
  expect_error({"process", sar, "-o", out, "--op", "lee", "--param", "radius=42"}, "out of range");
  expect_error({"process", sar, "-o", out, "--op", "lee", "--param", "colour=1"},
               "no parameter 'colour'");
  expect_error({"process", sar, "-o", out}, "--op");
  expect_error({"process", (dir / "missing.tif").string(), "-o", out, "--op", "lee"},
               "missing.tif");
  expect_error({"process", data("imagery/RGB.byte.tif"), "-o", out, "--op", "lee"}, "3 bands");
  expect_error({"process", sar, "-o", "/proc/relief/o.tif", "--op", "lee"}, "/proc/relief/o.tif");
  expect_error({"process", dir.path().string(), "-o", out, "--op", "lee"}, "not a relief store");
  expect_error({"process", sar, "-o", out, "--op", "lee", "--compress", "lzw"}, "--compress");
  auto list = run_relief({"process", "--list"});
  EXPECT_EQ(list.exit_code, 0);
  for (const char* op : {"lee",
                         "kuan",
                         "frost",
                         "gamma-map",
                         "median",
                         "gauss",
                         "mean",
                         "wavelet",
                         "rat",
                         "drago",
                         "tumblin",
                         "schlick",
                         "reinhard-devlin",
                         "chiu",
                         "retinex",
                         "ashikhmin",
                         "reinhard",
                         "durand",
                         "ext-schlick",
                         "ext-reinhard-devlin",
                         "amplitude-to-db"}) {
    EXPECT_NE(list.out.find(op), std::string::npos) << op;
  }
}

TEST(Process, StoresAreProcessedAndFusedFromTheCommandLine) {
  ScratchDir dir("process_store_cli");
  const std::string sar = (dir / "sar").string(), dem = (dir / "dem").string();
  ASSERT_EQ(
      run_relief({"build", data("sar/umbra_mount_yasur.tif"), "--kind", "sar", "-o", sar, "-q"})
          .exit_code,
      0);
  ASSERT_EQ(
      run_relief({"build", data("srtm/N42E001.hgt.zip"), "--kind", "elevation", "-o", dem, "-q"})
          .exit_code,
      0);
  const std::string out = (dir / "despeckled").string();
  auto r = run_relief({"process", sar, "-o", out, "--op", "gamma-map", "--param", "radius=3",
                       "--param", "looks=2", "-q"});
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_NE(r.out.find("tiles on 18 levels"), std::string::npos) << r.out;
  EXPECT_EQ(run_relief({"verify", out}).exit_code, 0);
  auto info = run_relief({"info", out});
  EXPECT_NE(info.out.find("relief process --op gamma-map radius=3 looks=2"), std::string::npos)
      << info.out;
  // A SAR operator on elevation, and an existing output: one-line errors.
  auto bad = run_relief({"process", dem, "-o", (dir / "x").string(), "--op", "lee"});
  EXPECT_NE(bad.exit_code, 0);
  EXPECT_NE(bad.err.find("expects SAR amplitude, linear, but the store holds elevation"),
            std::string::npos)
      << bad.err;
  bad = run_relief({"process", sar, "-o", out, "--op", "lee"});
  EXPECT_NE(bad.err.find("already exists"), std::string::npos) << bad.err;
  // Fusion.
  const std::string fused = (dir / "fused").string();
  r = run_relief({"fuse", dem, dem, "-o", fused, "--weights", "1,2", "-q"});
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_EQ(run_relief({"verify", fused}).exit_code, 0);
  for (const auto& [args, needle] : std::vector<std::pair<std::vector<std::string>, std::string>>{
           {{"fuse", dem, sar, "-o", (dir / "y").string()}, "holds sar data"},
           {{"fuse", dem, dem, "-o", (dir / "y").string(), "--weights", "1,x"}, "'x'"},
           {{"fuse", dem, dem, "-o", (dir / "y").string(), "--mode", "max"}, "--mode"},
           {{"fuse", dem, "-o", (dir / "y").string()}, "at least two"}}) {
    bad = run_relief(args);
    EXPECT_TRUE(is_one_line_error(bad, needle)) << needle << ": " << bad.err;
    EXPECT_FALSE(fs::exists(dir / "y"));
  }
}

TEST(Process, NodataEverywhereStaysNodata) {
  ScratchDir dir("process_nodata");
  const std::string in = (dir / "empty.tif").string(), out = (dir / "o.tif").string();
  const double gt[6] = {0, 1, 0, 0, 0, -1};
  write_geotiff(in, 50, 40, gt, std::vector<float>(2000, NAN));
  auto r = run_relief({"process", in, "-o", out, "--op", "lee", "--param", "radius=2", "-q"});
  ASSERT_EQ(r.exit_code, 0) << r.err;
  const Warped w = read_warped(out);
  for (double v : w.values) ASSERT_TRUE(std::isnan(v));
}

}  // namespace
}  // namespace relief::testing
