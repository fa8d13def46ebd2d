// White-box tests of the build's interior store: memory first, the disk only
// for what the budget pushes out, and what a resumed build finds.
#include "core_store.h"

#include <gtest/gtest.h>

#include <filesystem>

#include "../support/test_support.h"

namespace relief::ingest {
namespace {
namespace fs = std::filesystem;
using geo::TileKey;
using testing::regular_files_under;
using tiles::Raster;
using tiles::SampleType;

constexpr int kW = 16, kH = 8;
const tiles::TileShape kShape{SampleType::Float32, 1, kW, kH, 0};
constexpr uint64_t kCoreBytes = uint64_t{kW} * kH * 4;

Raster core_with(float base) {
  Raster r(SampleType::Float32, 1, kW, kH);
  auto v = r.f32();
  for (size_t i = 0; i < v.size(); ++i) v[i] = base + static_cast<float>(i);
  return r;
}

void expect_core(CoreStore& store, const TileKey& key, float base) {
  auto core = store.read(key);
  ASSERT_TRUE(core) << core.error().message;
  ASSERT_TRUE(*core) << key.to_string() << " is missing";
  const Raster expected = core_with(base);
  EXPECT_TRUE(std::equal((*core)->bytes().begin(), (*core)->bytes().end(), expected.bytes().begin(),
                         expected.bytes().end()))
      << key.to_string();
}

TEST(CoreStore, CoresWithinTheBudgetStayInMemory) {
  testing::ScratchDir dir("core_store_memory");
  CoreStore store(dir / "cores", kShape, 4 * kCoreBytes);
  for (uint32_t x = 0; x < 4; ++x) ASSERT_TRUE(store.write({5, x, 1}, core_with(100.0f * x)));
  EXPECT_EQ(regular_files_under(dir / "cores"), 0u);
  EXPECT_EQ(store.spilled(), 0u);
  EXPECT_FALSE(store.all_on_disk(5));
  EXPECT_TRUE(store.all_on_disk(4));  // nothing of that level
  EXPECT_EQ(store.list(5).size(), 4u);
  for (uint32_t x = 0; x < 4; ++x) {
    EXPECT_TRUE(store.exists({5, x, 1}));
    expect_core(store, {5, x, 1}, 100.0f * x);
  }
  EXPECT_FALSE(store.exists({5, 9, 1}));
  auto missing = store.read({5, 9, 1});
  ASSERT_TRUE(missing);
  EXPECT_EQ(*missing, nullptr);
}

TEST(CoreStore, CoresBeyondTheBudgetAreSpilledAndReadBack) {
  testing::ScratchDir dir("core_store_spill");
  CoreStore store(dir / "cores", kShape, 2 * kCoreBytes);
  for (uint32_t x = 0; x < 6; ++x) ASSERT_TRUE(store.write({5, x, 0}, core_with(10.0f * x)));
  // The least recently used went to disk; the last two are in memory only.
  EXPECT_EQ(store.spilled(), 4u);
  EXPECT_EQ(regular_files_under(dir / "cores"), 4u);
  EXPECT_FALSE(store.all_on_disk(5));
  ASSERT_EQ(store.list(5).size(), 6u);
  for (uint32_t x = 0; x < 6; ++x) expect_core(store, {5, x, 0}, 10.0f * x);
  // Reading the spilled ones back pushed the memory-only ones out in turn.
  EXPECT_EQ(store.spilled(), 6u);
  EXPECT_TRUE(store.all_on_disk(5));
  // A core read back from disk is not written again when it leaves memory.
  for (uint32_t x = 0; x < 6; ++x) expect_core(store, {5, x, 0}, 10.0f * x);
  EXPECT_EQ(store.spilled(), 6u);
}

TEST(CoreStore, AShrunkBudgetSpillsWhatNoLongerFitsButKeepsAFloor) {
  testing::ScratchDir dir("core_store_shrink");
  CoreStore store(dir / "cores", kShape, 40 * kCoreBytes);
  for (uint32_t x = 0; x < 20; ++x) ASSERT_TRUE(store.write({5, x, 0}, core_with(2.0f * x)));
  EXPECT_EQ(store.spilled(), 0u);
  ASSERT_TRUE(store.shrink_budget(22 * kCoreBytes));  // 18 cores' worth left
  EXPECT_EQ(store.budget(), 18 * kCoreBytes);
  EXPECT_EQ(store.spilled(), 2u);
  ASSERT_TRUE(store.shrink_budget(100 * kCoreBytes));  // never below 16 cores
  EXPECT_EQ(store.budget(), 16 * kCoreBytes);
  EXPECT_EQ(store.spilled(), 4u);
  EXPECT_EQ(regular_files_under(dir / "cores"), 4u);
  for (uint32_t x = 0; x < 20; ++x) expect_core(store, {5, x, 0}, 2.0f * x);
}

TEST(CoreStore, AResumedBuildFindsOnlyTheSpilledCores) {
  testing::ScratchDir dir("core_store_resume");
  {
    CoreStore killed(dir / "cores", kShape, 2 * kCoreBytes);
    for (uint32_t y = 0; y < 5; ++y) ASSERT_TRUE(killed.write({7, 3, y}, core_with(1.0f * y)));
    ASSERT_EQ(killed.spilled(), 3u);
  }  // the build dies with two cores in memory only
  CoreStore resumed(dir / "cores", kShape, 2 * kCoreBytes);
  const auto found = resumed.list(7);
  ASSERT_EQ(found.size(), 3u);
  for (uint32_t y = 0; y < 3; ++y) {
    EXPECT_EQ(found[y], (TileKey{7, 3, y}));
    EXPECT_TRUE(resumed.exists({7, 3, y}));
    expect_core(resumed, {7, 3, y}, 1.0f * y);
  }
  EXPECT_FALSE(resumed.exists({7, 3, 3}));
  EXPECT_FALSE(resumed.exists({7, 3, 4}));
  EXPECT_TRUE(resumed.all_on_disk(7));
}

}  // namespace
}  // namespace relief::ingest
