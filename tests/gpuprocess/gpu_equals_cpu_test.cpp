// Every GPU operator equals its libs/process counterpart on real tiles of the
// bundled SAR store, at the finest three levels (radii scaled per level),
// within 1e-4 relative; nodata where the CPU has nodata. One test per family
// (each test process builds the store once).
#include <gtest/gtest.h>

#include <fmt/format.h>

#include "gpu_fixture.h"

namespace relief::testing {
namespace {

struct Case {
  std::string op;
  std::vector<std::string> params;
  int tiles = 2;  // per level; 1 for operators slow on llvmpipe
};

void expect_all_equal(const std::vector<Case>& cases) {
  std::string errors;
  for (const Case& c : cases) {
    std::string name = c.op;
    for (const auto& p : c.params) name += " " + p;
    SCOPED_TRACE(name);
    ASSERT_TRUE(gpuprocess::runs_on_gpu(c.op));
    const double worst = expect_gpu_equals_cpu(chain_of({{c.op, c.params}}), 1e-4, c.tiles);
    errors += fmt::format("{}{}: {:.3g}", errors.empty() ? "" : ", ", name, worst);
  }
  ::testing::Test::RecordProperty("max_relative_errors", errors);
}

TEST(GpuEqualsCpu, Conversions) {
  expect_all_equal({{"amplitude-to-db", {}},
                    {"db-to-amplitude", {}},
                    {"amplitude-to-intensity", {}},
                    {"intensity-to-amplitude", {}}});
}

TEST(GpuEqualsCpu, GlobalMappings) {
  expect_all_equal({{"linear", {}},
                    {"linear", {"sigmas=1.5"}},
                    {"log", {}},
                    {"log", {"c=1000", "t_min=10", "t_max=5000"}},
                    {"gamma", {}},
                    {"gamma", {"gamma=0.2"}},
                    {"rat", {}},
                    {"drago", {}},
                    {"tumblin", {}},
                    {"schlick", {}},
                    {"schlick", {"b=50"}},
                    {"reinhard-devlin", {}},
                    {"reinhard-devlin", {"b=2", "c=0.5"}}});
}

TEST(GpuEqualsCpu, MeanLeeKuanGammaMap) {
  expect_all_equal({{"mean", {"radius=1"}},
                    {"mean", {"radius=8"}},
                    {"lee", {"radius=3", "looks=2"}},
                    {"lee", {"radius=8"}},
                    {"kuan", {"radius=3", "looks=3"}},
                    {"gamma-map", {"radius=3", "looks=2"}}});
}

TEST(GpuEqualsCpu, MedianGaussFrostWavelet) {
  expect_all_equal({{"median", {"radius=1"}},
                    {"median", {"radius=3"}, 1},
                    {"median", {"radius=4"}, 1},
                    {"gauss", {"radius=4"}},
                    {"gauss", {"radius=2", "sigma=3"}},
                    {"frost", {"radius=3"}},
                    {"frost", {"radius=2", "deramp=2"}},
                    {"wavelet", {"levels=1"}},
                    {"wavelet", {"levels=2", "k=2", "looks=3"}}});
}

TEST(GpuEqualsCpu, ExtendedSchlickAndReinhardDevlin) {
  expect_all_equal({{"ext-schlick", {"max_radius=4"}},
                    {"ext-schlick", {"max_radius=8", "d=0.8", "t=0.1"}},
                    {"ext-reinhard-devlin", {"max_radius=4"}},
                    {"ext-reinhard-devlin", {"max_radius=6", "b=1", "c=0.3", "d=0.9"}}});
}

// The classic local tone mappers on the same Gauss stack, and Durand's
// bilateral filter.
TEST(GpuEqualsCpu, ClassicLocalMappings) {
  expect_all_equal({{"chiu", {"radius=5"}},
                    {"chiu", {"c=0.5", "radius=2"}},
                    {"retinex", {"max_radius=8"}},
                    {"retinex", {"max_radius=5", "p=1000", "w=2", "range=1"}},
                    {"ashikhmin", {"max_radius=6"}},
                    {"ashikhmin", {"max_radius=5", "c=1000", "t=0.2"}},
                    {"reinhard", {"max_radius=6"}},
                    {"reinhard", {"max_radius=5", "c=2", "w=5", "s=4", "t=0.1"}},
                    {"durand", {"radius=3"}, 1},
                    {"durand", {"radius=5", "sigma_r=0.1", "k=0.6"}, 1}});
}

}  // namespace
}  // namespace relief::testing
