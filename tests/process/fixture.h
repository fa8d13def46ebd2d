#pragma once
// Images and operator runs shared by the process tests.
#include <string>
#include <vector>

#include "relief/process/operators.h"

namespace relief::process::testing {

struct Image {
  int width = 0, height = 0;
  std::vector<float> v;
  MutView view() { return {v.data(), width, height, width, 0, 0}; }
  ConstView cview() const { return {v.data(), width, height, width, 0, 0}; }
  float at(int x, int y) const { return v[static_cast<size_t>(y) * width + x]; }
};

// A window of the real Umbra SAR amplitude image (data/sar).
Image umbra_crop(int x0, int y0, int w, int h);
// Min, max, mean and population standard deviation of the valid samples.
GlobalStats stats_of(const Image& in);
// Runs an operator over `in`; the output is smaller by its margin on every
// side. Global statistics default to those of `in`.
Image run(const std::string& name, const std::vector<std::string>& params, const Image& in,
          Executor& ex, const GlobalStats* stats = nullptr);
// The quad-by-quad run of an operator (quads of qw x qh output samples, each
// with its own border) equals the whole image's run bit for bit.
void expect_quads_equal_whole(const std::string& name, const std::vector<std::string>& params,
                              const Image& in, Executor& ex);

}  // namespace relief::process::testing
