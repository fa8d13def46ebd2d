// The allocator under a small --memory budget, and the frames' heap made
// ready (allocator.h), for jemalloc and the system malloc alike. The kernel's
// per-process switch for huge pages applies whatever the allocator asked for
// with madvise, so it serves jemalloc and the system malloc alike.
#include <cstdlib>
#include <string>
#include <vector>

#include <malloc.h>
#include <sys/prctl.h>

#include "allocator.h"

namespace relief::cli {

namespace {
constexpr uint64_t kSmallBudget = uint64_t{512} << 20;
uint64_t prefaulted = 0;  // by prefault_frame_heap()
}  // namespace

std::string prefault_note() {
  if (prefaulted == 0) return "";
  return "; " + std::to_string(prefaulted >> 20) + " MiB of heap faulted in";
}

void touch_pages(void* p, uint64_t bytes) {
  auto* page = static_cast<volatile char*>(p);  // volatile: the stores happen
  for (uint64_t i = 0; i < bytes; i += 4096) page[i] = 0;
}

void prefault_frame_heap(uint64_t bytes) {
  // Blocks of 1 MiB: with jemalloc's default a free block served a request
  // at most 64 times smaller, so larger blocks were left to the few large
  // requests (4 MiB blocks measured no better than none); relief's setting
  // now lets them serve requests down to 4096 times smaller
  // (allocator_jemalloc.cpp), which the frames' small slabs need.
  constexpr size_t kBlock = size_t{1} << 20;
  std::vector<void*> blocks;
  for (uint64_t done = 0; done < bytes; done += kBlock) {
    void* p = std::malloc(kBlock);
    if (!p) break;
    touch_pages(p, kBlock);
    blocks.push_back(p);
  }
  for (void* p : blocks) std::free(p);
  prefaulted += blocks.size() * kBlock;
}

void give_up_huge_pages() {
  // Pages already huge stay huge; the ones touched from here on do not.
  ::prctl(PR_SET_THP_DISABLE, 1, 0, 0, 0);
}

void fit_allocator_to_budget(uint64_t budget_bytes) {
  if (budget_bytes >= kSmallBudget) return;
  give_up_huge_pages();
  // glibc's malloc gives each thread that meets contention an arena of its
  // own (up to 8 per core), and memory freed in one is not reused by the
  // others: a 128 MiB build peaked at 134-139 MiB, with two arenas at
  // 108-116 MiB and no slower. A no-op when jemalloc serves malloc.
  ::mallopt(M_ARENA_MAX, 2);
}

}  // namespace relief::cli
