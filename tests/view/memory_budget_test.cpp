// One memory budget split among the scene's caches: the shares add up to at
// most the total, each cache gets room for about as many tiles as the others
// (by its bytes per sample), L3 takes a share only where it is main memory
// and no budget of its own was given, and totals too small are refused with
// the option's name.
#include <gtest/gtest.h>

#include "relief/view/memory_budget.h"

namespace relief::view {
namespace {

constexpr uint64_t kMiB = uint64_t{1} << 20;

uint64_t sum(const CacheBudgets& b, int textures) {
  return b.elevation + b.diamond_errors + b.texture_each * textures + b.gpu.value_or(0);
}

TEST(MemoryBudget, SharesFollowEachCachesBytesPerTile) {
  CacheUse use;
  use.diamond_errors = true;
  use.gpu_in_memory = true;
  const CacheBudgets b = *split_memory_budget(512 * kMiB, use);
  ASSERT_TRUE(b.gpu);
  EXPECT_LE(sum(b, 0), 512 * kMiB);
  EXPECT_GE(sum(b, 0), 512 * kMiB - 4);  // rounding down only
  // 4.4 : 16 : 8.9 bytes per sample (decoded heights, diamond errors, L3).
  EXPECT_NEAR(static_cast<double>(b.diamond_errors) / b.elevation, 16 / 4.4, 1e-6);
  EXPECT_NEAR(static_cast<double>(*b.gpu) / b.elevation, 8.9 / 4.4, 1e-6);
  EXPECT_EQ(b.texture_each, 0u);
}

TEST(MemoryBudget, TheGpuCountsOnlyWhereItIsMainMemory) {
  CacheUse use;
  use.diamond_errors = true;
  const CacheBudgets gpu_card = *split_memory_budget(256 * kMiB, use);
  EXPECT_FALSE(gpu_card.gpu);  // --gpu-budget (or its default) decides L3
  EXPECT_GE(sum(gpu_card, 0), 256 * kMiB - 2);

  use.gpu_in_memory = true;
  use.gpu_given = 100 * kMiB;  // given: counted, not split
  const CacheBudgets given = *split_memory_budget(256 * kMiB, use);
  EXPECT_FALSE(given.gpu);
  EXPECT_LE(sum(given, 0), 156 * kMiB);
  EXPECT_GE(sum(given, 0), 156 * kMiB - 2);
}

TEST(MemoryBudget, TexturesAndNoRefinement) {
  CacheUse use;
  use.textures = 3;
  use.composites = true;
  use.gpu_in_memory = true;
  const CacheBudgets b = *split_memory_budget(1024 * kMiB, use);
  EXPECT_EQ(b.diamond_errors, 0u);         // quads: no diamond errors
  EXPECT_EQ(b.texture_each, b.elevation);  // decoded RGBA and float: 4.4 bytes a sample each
  EXPECT_LE(sum(b, 3), 1024 * kMiB);
  EXPECT_NEAR(static_cast<double>(*b.gpu) / b.elevation, (8.9 + 4.4) / 4.4, 1e-6);
}

TEST(MemoryBudget, TooSmallATotalIsRefusedByName) {
  CacheUse use;
  const auto small = split_memory_budget(kMinimumMemoryBudget - 1, use);
  ASSERT_FALSE(small);
  EXPECT_NE(small.error().message.find("--memory-budget"), std::string::npos);
  EXPECT_TRUE(split_memory_budget(kMinimumMemoryBudget, use));

  use.gpu_in_memory = true;
  use.gpu_given = 120 * kMiB;  // leaves 8 MiB beside it
  const auto crowded = split_memory_budget(128 * kMiB, use);
  ASSERT_FALSE(crowded);
  EXPECT_NE(crowded.error().message.find("--gpu-budget"), std::string::npos);
}

}  // namespace
}  // namespace relief::view
