// Every GPU operator equals its libs/process counterpart on real tiles of the
// bundled SAR store, at the finest three levels (radii scaled per level),
// within 1e-4 relative; nodata where the CPU has nodata.
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
void PrintTo(const Case& c, std::ostream* os) {
  *os << c.op;
  for (const auto& p : c.params) *os << " " << p;
}

class GpuEqualsCpu : public ::testing::TestWithParam<Case> {};

TEST_P(GpuEqualsCpu, OnTilesOfThreeLevels) {
  const Case& c = GetParam();
  ASSERT_TRUE(gpuprocess::runs_on_gpu(c.op));
  const double worst = expect_gpu_equals_cpu(chain_of({{c.op, c.params}}), 1e-4, c.tiles);
  RecordProperty("max_relative_error", fmt::format("{:.3g}", worst));
}

std::string case_name(const ::testing::TestParamInfo<Case>& info) {
  std::string name = info.param.op;
  for (const auto& p : info.param.params) name += "_" + p;
  for (char& ch : name) {
    if (!std::isalnum(static_cast<unsigned char>(ch))) ch = '_';
  }
  return name;
}

INSTANTIATE_TEST_SUITE_P(Conversions, GpuEqualsCpu,
                         ::testing::Values(Case{"amplitude-to-db", {}},
                                           Case{"amplitude-to-intensity", {}},
                                           Case{"intensity-to-amplitude", {}}),
                         case_name);

INSTANTIATE_TEST_SUITE_P(
    GlobalMappings, GpuEqualsCpu,
    ::testing::Values(Case{"linear", {}}, Case{"linear", {"sigmas=1.5"}}, Case{"log", {}},
                      Case{"log", {"c=1000", "t_min=10", "t_max=5000"}}, Case{"gamma", {}},
                      Case{"gamma", {"gamma=0.2"}}, Case{"rat", {}}, Case{"drago", {}},
                      Case{"tumblin", {}}, Case{"schlick", {}}, Case{"schlick", {"b=50"}},
                      Case{"reinhard-devlin", {}}, Case{"reinhard-devlin", {"b=2", "c=0.5"}}),
    case_name);

INSTANTIATE_TEST_SUITE_P(
    SpeckleFilters, GpuEqualsCpu,
    ::testing::Values(Case{"mean", {"radius=1"}}, Case{"mean", {"radius=8"}},
                      Case{"lee", {"radius=3", "looks=2"}}, Case{"lee", {"radius=8"}},
                      Case{"median", {"radius=1"}}, Case{"median", {"radius=3"}, 1},
                      Case{"median", {"radius=6"}, 1}, Case{"gauss", {"radius=4"}},
                      Case{"gauss", {"radius=2", "sigma=3"}}, Case{"kuan", {"radius=3", "looks=3"}},
                      Case{"frost", {"radius=3"}}, Case{"frost", {"radius=2", "deramp=2"}},
                      Case{"gamma-map", {"radius=3", "looks=2"}}, Case{"wavelet", {"levels=1"}},
                      Case{"wavelet", {"levels=2", "k=2", "looks=3"}}),
    case_name);

INSTANTIATE_TEST_SUITE_P(LocalMappings, GpuEqualsCpu,
                         ::testing::Values(Case{"ext-schlick", {"max_radius=4"}},
                                           Case{"ext-schlick", {"max_radius=8", "d=0.8", "t=0.1"}},
                                           Case{"ext-reinhard-devlin", {"max_radius=4"}},
                                           Case{"ext-reinhard-devlin",
                                                {"max_radius=6", "b=1", "c=0.3", "d=0.9"}}),
                         case_name);

// The classic local tone mappers on the same Gauss stack.
INSTANTIATE_TEST_SUITE_P(
    ClassicLocalMappings, GpuEqualsCpu,
    ::testing::Values(Case{"chiu", {"radius=5"}}, Case{"chiu", {"c=0.5", "radius=2"}},
                      Case{"retinex", {"max_radius=8"}},
                      Case{"retinex", {"max_radius=5", "p=1000", "w=2", "range=1"}},
                      Case{"ashikhmin", {"max_radius=6"}},
                      Case{"ashikhmin", {"max_radius=8", "c=1000", "t=0.2"}},
                      Case{"reinhard", {"max_radius=6"}},
                      Case{"reinhard", {"max_radius=8", "c=2", "w=5", "s=4", "t=0.1"}},
                      Case{"durand", {}, 1},
                      Case{"durand", {"radius=8", "sigma_r=0.1", "k=0.6"}, 1}),
    case_name);

}  // namespace
}  // namespace relief::testing
