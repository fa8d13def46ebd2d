#include "relief/view/memory_budget.h"

#include <fmt/format.h>

namespace relief::view {

namespace {

// Bytes per sample of a 512 x 256 tile in each cache, as measured on the
// bench stores (a decoded tile keeps its one-sample border; the diamond
// errors are 8-byte records of about two diamonds per sample; L3 holds R32F
// heights and RG16F slopes per texel, or RGBA8).
constexpr double kDecodedHeights = 4.4;
constexpr double kDiamondErrors = 16.0;
constexpr double kDecodedTexture = 4.4;
constexpr double kGpuHeights = 8.9;
constexpr double kGpuTexture = 4.4;

std::string mib(uint64_t bytes) {
  return fmt::format("{:.0f} MiB", static_cast<double>(bytes) / (1 << 20));
}

}  // namespace

Result<CacheBudgets> split_memory_budget(uint64_t total, const CacheUse& use) {
  if (total < kMinimumMemoryBudget) {
    return fail(fmt::format("--memory-budget: {} is below the smallest budget, {}", mib(total),
                            mib(kMinimumMemoryBudget)));
  }
  const bool gpu_share = use.gpu_in_memory && !use.gpu_given;
  uint64_t rest = total;
  if (use.gpu_in_memory && use.gpu_given) {
    if (*use.gpu_given + kMinimumMemoryBudget > total) {
      return fail(fmt::format(
          "--memory-budget: {} leaves less than {} beside --gpu-budget {} (on a software "
          "rasteriser the GPU cache is main memory)",
          mib(total), mib(kMinimumMemoryBudget), mib(*use.gpu_given)));
    }
    rest -= *use.gpu_given;
  }
  const double errors = use.diamond_errors ? kDiamondErrors : 0;
  const double textures = use.textures * kDecodedTexture;
  const double gpu =
      gpu_share ? kGpuHeights + ((use.textures > 0 || use.composites) ? kGpuTexture : 0) : 0;
  const double per_sample = kDecodedHeights + errors + textures + gpu;
  const auto share = [&](double weight) {
    return static_cast<uint64_t>(static_cast<double>(rest) * weight / per_sample);
  };
  CacheBudgets b;
  b.elevation = share(kDecodedHeights);
  b.diamond_errors = share(errors);
  b.texture_each = use.textures > 0 ? share(kDecodedTexture) : 0;
  if (gpu_share) b.gpu = share(gpu);
  return b;
}

}  // namespace relief::view
