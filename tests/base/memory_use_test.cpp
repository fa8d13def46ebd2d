#include "relief/base/memory_use.h"

#include <gtest/gtest.h>

#include <cstddef>
#include <cstdlib>
#include <numeric>
#include <vector>

namespace relief {
namespace {

// Populating pages must never change what they hold: it is called on rasters
// whose samples are already written (memory reused by the allocator).
TEST(PopulatePages, KeepsTheBytesOfMemoryAlreadyWritten) {
  std::vector<unsigned char> bytes(size_t{3} << 20);
  std::iota(bytes.begin(), bytes.end(), static_cast<unsigned char>(7));
  const std::vector<unsigned char> before = bytes;
  populate_pages(bytes.data() + 1, bytes.size() - 1);  // an unaligned start
  EXPECT_EQ(bytes, before);
}

TEST(PopulatePages, FreshMemoryIsWritableAfterwards) {
  constexpr size_t kSize = size_t{2} << 20;
  auto* p = static_cast<unsigned char*>(std::malloc(kSize));
  ASSERT_NE(p, nullptr);
  populate_pages(p, kSize);
  populate_pages(p, 100);  // below the minimum: nothing to do
  for (size_t i = 0; i < kSize; i += 4096) p[i] = static_cast<unsigned char>(i >> 12);
  for (size_t i = 0; i < kSize; i += 4096) EXPECT_EQ(p[i], static_cast<unsigned char>(i >> 12));
  std::free(p);
}

TEST(MemoryUse, ResidentSetIsReported) {
  EXPECT_GT(resident_set_bytes(), 0u);
}

TEST(MemoryUse, ThePeakIsAtLeastWhatIsResidentNow) {
  // 32 MiB written: both figures see them, and the peak never falls below.
  std::vector<char> block(size_t{32} << 20, 1);
  const uint64_t now = resident_set_bytes();
  EXPECT_GE(now, uint64_t{32} << 20);
  EXPECT_GE(peak_resident_set_bytes(), now - (uint64_t{1} << 20));  // pages read apart
  EXPECT_EQ(block[12345], 1);
}

}  // namespace
}  // namespace relief
