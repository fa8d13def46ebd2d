// The allocator under a small --memory budget (allocator.h). The kernel's
// per-process switch for huge pages applies whatever the allocator asked for
// with madvise, so it serves jemalloc and the system malloc alike.
#include <malloc.h>
#include <sys/prctl.h>

#include "allocator.h"

namespace relief::cli {

namespace {
constexpr uint64_t kSmallBudget = uint64_t{512} << 20;
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
