// White-box tests of the build's memory governor, on an injected resident
// size: nothing below the mark; above it the allocator's freed pages first,
// then the caches by the excess.
#include "memory_governor.h"

#include <gtest/gtest.h>

#include <vector>

namespace relief::ingest {
namespace {

constexpr uint64_t kMiB = uint64_t{1} << 20;

struct Fake {
  uint64_t resident = 0;
  uint64_t freed = 0;  // what a release gives back
  int releases = 0;
  std::vector<uint64_t> shrinks;

  MemoryGovernor::Hooks hooks(bool with_release = true) {
    MemoryGovernor::Hooks h;
    h.resident = [this] { return resident; };
    if (with_release) {
      h.release = [this] {
        ++releases;
        resident -= freed;
      };
    }
    h.shrink = [this](uint64_t bytes) -> Status {
      shrinks.push_back(bytes);
      return {};
    };
    return h;
  }
};

TEST(MemoryGovernor, TheMarkSitsAMarginUnderTheBudget) {
  Fake fake;
  EXPECT_EQ(MemoryGovernor(256 * kMiB, fake.hooks()).mark(), 240 * kMiB);
  EXPECT_EQ(MemoryGovernor(32 * kMiB, fake.hooks()).mark(), 28 * kMiB);  // at least 4 MiB
}

TEST(MemoryGovernor, UnderTheMarkNothingHappens) {
  Fake fake;
  fake.resident = 200 * kMiB;
  MemoryGovernor governor(256 * kMiB, fake.hooks());
  ASSERT_TRUE(governor.check());
  EXPECT_EQ(fake.releases, 0);
  EXPECT_TRUE(fake.shrinks.empty());
}

TEST(MemoryGovernor, FreedPagesGoBackBeforeAnyCacheShrinks) {
  Fake fake;
  fake.resident = 250 * kMiB;
  fake.freed = 20 * kMiB;
  MemoryGovernor governor(256 * kMiB, fake.hooks());
  ASSERT_TRUE(governor.check());
  EXPECT_EQ(fake.releases, 1);
  EXPECT_TRUE(fake.shrinks.empty());
  EXPECT_EQ(governor.releases(), 1u);
}

TEST(MemoryGovernor, TheCachesGiveUpWhatReleasingCouldNot) {
  Fake fake;
  fake.resident = 270 * kMiB;
  fake.freed = 10 * kMiB;
  MemoryGovernor governor(256 * kMiB, fake.hooks());
  ASSERT_TRUE(governor.check());
  ASSERT_EQ(fake.shrinks.size(), 1u);
  EXPECT_EQ(fake.shrinks[0], 20 * kMiB);  // 260 resident against a mark of 240
  EXPECT_EQ(governor.shrunk_bytes(), 20 * kMiB);
}

TEST(MemoryGovernor, WithoutAReleaseTheCachesShrinkAtOnce) {
  Fake fake;
  fake.resident = 250 * kMiB;
  MemoryGovernor governor(256 * kMiB, fake.hooks(false));
  ASSERT_TRUE(governor.check());
  ASSERT_EQ(fake.shrinks.size(), 1u);
  EXPECT_EQ(fake.shrinks[0], 10 * kMiB);
}

TEST(MemoryGovernor, AnUnknownResidentSizeChangesNothing) {
  Fake fake;  // resident 0: /proc not readable
  MemoryGovernor governor(256 * kMiB, fake.hooks());
  ASSERT_TRUE(governor.check());
  EXPECT_EQ(fake.releases, 0);
  EXPECT_TRUE(fake.shrinks.empty());
}

TEST(MemoryGovernor, AFailedSpillIsReported) {
  Fake fake;
  fake.resident = 300 * kMiB;
  MemoryGovernor::Hooks hooks = fake.hooks(false);
  hooks.shrink = [](uint64_t) -> Status { return fail("cores: cannot write: disk full"); };
  MemoryGovernor governor(256 * kMiB, std::move(hooks));
  const Status status = governor.check();
  ASSERT_FALSE(status);
  EXPECT_EQ(status.error().message, "cores: cannot write: disk full");
}

}  // namespace
}  // namespace relief::ingest
